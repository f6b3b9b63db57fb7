#!/usr/bin/env bash
# daemon_bench.sh — findmugd under replayed real frames: sustained fps, latency,
# drops, time per stage, CPU and peak memory, threaded vs sequential.
#
#   tests/bench/daemon_bench.sh [--build-dir build] [--rates "1 5 15 30"] [--duration 30]
#       [--datasets "nyu pcl synth"] [--modes "threaded sequential"] [--no-search]
#       [--model FILE] [--out BENCHMARKS-replay.md] [--results DIR] [--tables-only]
#       [--set KEY=VALUE]...   (extra daemon settings, e.g. --set daemon.max_cpu_cores=1)
#       [--robot-pose X,Y,YAW] (findmug-replay also publishes this fixed robot pose with
#                               every frame: what daemon.semantic_map / the table map need)
#       [--raw-frames]         (findmug-replay sends frames uncompressed, as a camera on the
#                               robot PC hands them over: no JPEG or zlib decoding in the daemon;
#                               default: depth zlib, colour JPEG, as an LCM camera driver sends)
#       [--objects]            (objects on: an object taught with findmug-teach from the first
#                               NYU frame it can teach from, in daemon.objects_dir, so every
#                               frame's candidates go through the matcher; with the robot pose
#                               (0,0,0 unless --robot-pose) the object map runs and is published)
#   (scripts/bench.sh runs this with the defaults.)
#
# For each data set, input rate and mode, inside a private network namespace:
#   findmug-replay publishes the data set's frames in a loop at RATE fps for
#   DURATION s on udpm (as a camera driver would: fresh seq, utime = send time);
#   the daemon under test reads them with its lcm: source and publishes labels;
#   findmug-replay-probe measures latency (label received - frame received),
#   output fps and drops, and keeps the daemon's final status (per-stage times
#   over the whole run, counters). CPU time and peak RSS of the daemon process
#   come from /proc (sampled every 0.2 s; VmHWM is the kernel's own peak).
# Modes: "threaded" = findmugd; "sequential" = findmug-sequential, the same
# library, config and LCM I/O with every stage on one thread (the gain from
# pipelining is the ratio of the two).
# Data sets: nyu = the 31 NYU Depth V2 frames (640x480) looped; pcl = PCL's
# 3-frame Kinect grabber sequence (PCLZF) looped; synth = a 60-frame synthetic
# apartment walk (findmug-synth --seed 7), looped.
# Then, unless --no-search, the highest NYU input rate the threaded daemon
# holds without drops is searched by bisection between the grid's rates.
#
# Writes a Markdown fragment (machine, commit, command, tables) to --out and
# the raw reports (JSON, histograms, logs) under --results; --tables-only
# rewrites the fragment from an existing --results directory without running. Figures depend on
# what else runs on the machine: the load average is recorded with them.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build}"
RATES="1 5 15 30"
DURATION=30
DATASETS="nyu pcl synth"
MODES="threaded sequential"
SEARCH=1
TABLES_ONLY=0
MODEL="${FINDMUG_MODEL:-}"
OUT="$ROOT/BENCHMARKS-replay.md"
RESULTS=""
EXTRA_SETS=()
REPLAY_POSE=()
REPLAY_CODEC=()
OBJECTS=0
COMMAND_LINE="tests/bench/daemon_bench.sh $*"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) BUILD=$2; shift 2 ;;
    --rates) RATES=$2; shift 2 ;;
    --duration) DURATION=$2; shift 2 ;;
    --datasets) DATASETS=$2; shift 2 ;;
    --modes) MODES=$2; shift 2 ;;
    --no-search) SEARCH=0; shift ;;
    --tables-only) TABLES_ONLY=1; shift ;;
    --model) MODEL=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --results) RESULTS=$2; shift 2 ;;
    --set) EXTRA_SETS+=(--set "$2"); shift 2 ;;
    --robot-pose) REPLAY_POSE=(--robot-pose "$2"); shift 2 ;;
    --objects) OBJECTS=1; shift ;;
    --raw-frames) REPLAY_CODEC=(--depth-compression none --color-compression none); shift ;;
    -h|--help) sed -n '2,40p' "$0"; exit 0 ;;
    *) echo "daemon_bench: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
BUILD="$(cd "$BUILD" && pwd)"
FINDMUGD="$BUILD/daemon/findmugd"
# The replay programs live in tools/replay; a base build of an older commit
# (budget_compare.sh) has them in tests/replay.
REPLAY_DIR="$BUILD/tools/replay"
[[ -x "$REPLAY_DIR/findmug-replay" || ! -x "$BUILD/tests/replay/findmug-replay" ]] ||
  REPLAY_DIR="$BUILD/tests/replay"
SEQUENTIAL="$REPLAY_DIR/findmug-sequential"
REPLAY="$REPLAY_DIR/findmug-replay"
PROBE="$REPLAY_DIR/findmug-replay-probe"
SYNTH="$BUILD/tools/findmug-synth"
TEACH="$BUILD/tools/findmug-teach"
TRAIN="$BUILD/tools/findmug-train"
for exe in "$FINDMUGD" "$SEQUENTIAL" "$REPLAY" "$PROBE"; do
  [[ -x "$exe" ]] || { echo "daemon_bench: $exe missing: build first (cmake --build $BUILD)" >&2; exit 1; }
done

# --- private network namespace (no packet leaves it) -------------------------------
if [[ "${FINDMUG_BENCH_NETNS:-}" != 1 ]]; then
  ns=(unshare --net)
  [[ $EUID -eq 0 ]] || ns=(unshare --net --map-root-user)
  exec "${ns[@]}" env FINDMUG_BENCH_NETNS=1 FINDMUG_BENCH_COMMAND="$COMMAND_LINE" \
    BUILD_DIR="$BUILD" bash "$0" "${ARGS[@]}"
fi
COMMAND_LINE="${FINDMUG_BENCH_COMMAND:-$COMMAND_LINE}"
ip link set lo up
ip route add 224.0.0.0/4 dev lo
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"

DATA_ROOT="${FINDMUG_DATA:-$ROOT/../shared/data}"
WORK="$(mktemp -d /tmp/findmug-bench.XXXXXX)"
RESULTS="${RESULTS:-$BUILD/bench-results/daemon-$(date -u +%Y%m%dT%H%M%SZ)}"
mkdir -p "$RESULTS"
PIDS=()
cleanup() {
  for pid in "${PIDS[@]+"${PIDS[@]}"}"; do kill -TERM "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
forget() {
  local keep=() p
  for p in "${PIDS[@]+"${PIDS[@]}"}"; do [[ "$p" == "$1" ]] || keep+=("$p"); done
  PIDS=("${keep[@]+"${keep[@]}"}")
}
log() { echo "daemon_bench: $*" >&2; }

wait_for() {  # FILE SECONDS PID
  local file=$1 seconds=$2 pid=$3 waited=0
  while [[ ! -e "$file" ]]; do
    kill -0 "$pid" 2>/dev/null || return 2
    (( waited >= seconds * 5 )) && return 1
    sleep 0.2
    waited=$((waited + 1))
  done
}

# monitor PID FILE: "epoch_ms cpu_ticks vmhwm_kb map_ticks objects_ticks" every 0.2 s while
# PID lives; map_ticks = CPU ticks of the semantic map thread ("findmug-semmap"), objects_ticks
# those of the object work's thread ("findmug-objects"); 0 without them. Bash builtins only
# (read, no cat/awk/date/sleep): forking a dozen programs every 0.2 s cost ~10 % of a core, on
# the same two cores as the daemon it measures.
procTicks() {  # STAT_FILE -> utime + stime in REPLY, 1 if unreadable
  local stat fields
  read -r stat 2>/dev/null < "$1" || return 1
  # Fields after the command name (which may hold spaces): utime is 12th, stime 13th there.
  read -r -a fields <<< "${stat##*) }"
  REPLY=$((fields[11] + fields[12]))
}
monitor() {
  local pid=$1 file=$2 ticks hwm map objects task comm key value unit tick_fd
  local tick_fifo="$WORK/monitor-$BASHPID.fifo"
  mkfifo "$tick_fifo" && exec {tick_fd}<>"$tick_fifo"  # read -t on it: a sleep without a fork
  : > "$file"
  while procTicks "/proc/$pid/stat"; do
    ticks=$REPLY hwm="" map=0 objects=0
    while read -r key value unit; do
      [[ $key == VmHWM: ]] && { hwm=$value; break; }
    done 2>/dev/null < "/proc/$pid/status" || true
    for task in /proc/$pid/task/*; do
      read -r comm 2>/dev/null < "$task/comm" || continue
      if [[ $comm == findmug-semmap ]]; then
        procTicks "$task/stat" && map=$REPLY
      elif [[ $comm == findmug-objects ]]; then
        procTicks "$task/stat" && objects=$REPLY
      fi
    done
    [[ -n "$hwm" ]] && echo "$(( ${EPOCHREALTIME//[!0-9]/} / 1000 )) $ticks $hwm $map $objects" >> "$file"
    read -r -t 0.2 -u "$tick_fd" _ || true
  done
}

# --- data sets ---------------------------------------------------------------------------
declare -A SPEC
for ds in $DATASETS; do
  case "$ds" in
    nyu) SPEC[nyu]="dataset:$DATA_ROOT/nyuv2_labeled" ;;
    pcl) SPEC[pcl]="pclzf:$DATA_ROOT/pcl_test_clouds/grabber_sequences/pclzf" ;;
    synth)
      if [[ $TABLES_ONLY == 1 ]]; then SPEC[synth]="(not run)"; continue; fi
      [[ -x "$SYNTH" ]] || { log "findmug-synth missing"; exit 1; }
      log "rendering the synthetic apartment (60 frames)"
      "$SYNTH" --seed 7 --frames 60 --out "$WORK/synth" > "$WORK/synth.log" 2>&1 \
        || { cat "$WORK/synth.log"; exit 1; }
      SPEC[synth]="dataset:$WORK/synth" ;;
    *) log "unknown data set '$ds' (nyu, pcl, synth)"; exit 2 ;;
  esac
done

MODEL_SETS=()
if [[ -z "$MODEL" ]]; then
  [[ -f "$ROOT/models/findmug.fmf" ]] && MODEL="$ROOT/models/findmug.fmf"
  # The shipped model's settings (models/README.md: region, scene and object features,
  # NYU-13 classes, the learned pairwise term); findmugd refuses a model whose stages
  # differ from its config. Also daemon/findmugd.yaml's object consistency and depth
  # fill, so that the rows are the shipped labelling.
  [[ -n "$MODEL" ]] && MODEL_SETS=(--set features.regions=true --set features.scene=true
                                   --set learner.classes=nyu13 --set features.objects=true
                                   --set features.objects_columns=relations
                                   --set mrf.object_consistency=0.5 --set mrf.pairwise=context
                                   --set cloud.fill_depth_max_run_px=40)
fi
if [[ -z "$MODEL" && $TABLES_ONLY == 0 ]]; then
  MODEL="$RESULTS/nyu31.fmf"
  log "no committed model: training $MODEL on the 31 NYU frames (default forest)"
  "$TRAIN" --data "$DATA_ROOT/nyuv2_labeled" --set ground.source=floor_labels --out "$MODEL" \
    > "$RESULTS/train.log" 2>&1 || { cat "$RESULTS/train.log"; exit 1; }
fi

# The checkout may change while the benchmark runs: every run uses this copy.
if [[ $TABLES_ONLY == 0 ]]; then
  cp "$MODEL" "$RESULTS/model.fmf"
  MODEL_NAME="$(basename "$MODEL")"
  echo "$MODEL_NAME" > "$RESULTS/model-name"
  MODEL="$RESULTS/model.fmf"
else
  MODEL_NAME="$(cat "$RESULTS/model-name" 2>/dev/null || basename "$MODEL")"
fi

# --- objects on: a taught object -----------------------------------------------------------
if [[ $OBJECTS == 1 && $TABLES_ONLY == 0 ]]; then
  [[ -x "$TEACH" ]] || { log "findmug-teach missing: build it first"; exit 1; }
  mkdir -p "$RESULTS/objects"
  # The first NYU frame with a candidate on a table to teach from: a model of something that
  # is on NYU's tables, so that candidates get past the cheap gates to the shape descriptor.
  taught=""
  for png in "$DATA_ROOT"/nyuv2_labeled/rgb/*.png; do
    f=$(basename "$png" .png)
    if "$TEACH" --name nyu_object --data "$DATA_ROOT/nyuv2_labeled" --frames "$f" \
         --model "$MODEL" "${MODEL_SETS[@]}" --out "$RESULTS/objects/nyu_object.fmo" \
         > "$RESULTS/teach.log" 2>&1; then
      taught=$f; break
    fi
  done
  [[ -n "$taught" ]] || { cat "$RESULTS/teach.log"; log "no NYU frame to teach an object from"; exit 1; }
  echo "$taught" > "$RESULTS/objects/taught-from"
  log "objects on: taught nyu_object from NYU frame $taught"
  EXTRA_SETS+=(--set "daemon.objects_dir=$RESULTS/objects")
  [[ ${#REPLAY_POSE[@]} -gt 0 ]] || REPLAY_POSE=(--robot-pose 0,0,0)
fi

# --- one run -------------------------------------------------------------------------------
# run_one DS RATE MODE: results in $RESULTS/DS-RATEfps-MODE/
run_one() {
  local ds=$1 rate=$2 mode=$3
  local tag="$ds-${rate}fps-$mode" dir="$RESULTS/$ds-${rate}fps-$mode"
  rm -rf "$dir"; mkdir -p "$dir"
  log "$tag: ${DURATION} s"
  "$PROBE" --url "$URL" --live --expect-file "$dir/count" --name "$tag" --report-only \
    --ready-file "$dir/ready" --drained-file "$dir/drained" --out-json "$dir/probe.json" \
    --histogram-csv "$dir/histogram.csv" --histogram-txt "$dir/histogram.txt" --bins 60 \
    --timeout $((DURATION + 900)) > "$dir/probe.log" 2>&1 &
  local probe=$!; PIDS+=("$probe")
  local exe=$FINDMUGD trace=()
  [[ $mode == sequential ]] && exe=$SEQUENTIAL
  # Where each frame's time went (frame_trace.hpp), when the build has the setting.
  [[ $mode == threaded ]] && grep -qa daemon.frame_trace_file "$exe" &&
    trace=(--set "daemon.frame_trace_file=$dir/frame-trace.csv")
  "$exe" --source "lcm:FINDMUG_RGBD?url=$URL" --lcm-url "$URL" --model "$MODEL" \
    "${MODEL_SETS[@]}" --set daemon.stats_window_s=3600 "${trace[@]+"${trace[@]}"}" \
    "${EXTRA_SETS[@]+"${EXTRA_SETS[@]}"}" \
    --log-level warn > "$dir/daemon.log" 2>&1 &
  local daemon=$!; PIDS+=("$daemon")
  monitor "$daemon" "$dir/usage" &
  local mon=$!; PIDS+=("$mon")
  if ! wait_for "$dir/ready" 120 "$daemon"; then
    # Recorded and skipped: one failed configuration must not lose the others.
    tail -5 "$dir/daemon.log" >&2; log "$tag: the daemon did not come up; run skipped"
    kill -TERM "$daemon" "$probe" 2>/dev/null || true
    wait "$daemon" "$probe" "$mon" 2>/dev/null || true
    forget "$daemon"; forget "$probe"; forget "$mon"
    rm -f "$dir/probe.json"
    return 1
  fi
  date +%s%3N > "$dir/start_ms"
  "$REPLAY" --source "${SPEC[$ds]}" --rate "$rate" --duration "$DURATION" --url "$URL" \
    "${REPLAY_POSE[@]+"${REPLAY_POSE[@]}"}" "${REPLAY_CODEC[@]+"${REPLAY_CODEC[@]}"}" --count-file "$dir/count" > "$dir/replay.log" 2>&1 || { cat "$dir/replay.log" >&2; exit 1; }
  # Let queued frames finish (a slow mode may need a while), then stop.
  wait_for "$dir/drained" 120 "$daemon" || log "$tag: not drained after 120 s, stopping"
  date +%s%3N > "$dir/end_ms"
  kill -TERM "$daemon" 2>/dev/null || true; wait "$daemon" || log "$tag: daemon exit code $?"; forget "$daemon"
  wait "$mon" || true; forget "$mon"
  kill -TERM "$probe" 2>/dev/null || true; wait "$probe" || true; forget "$probe"
  grep -E "^== |latency ms|daemon status" "$dir/probe.log" >&2 || true
}

# Figures of one run as "key=value" lines.
figures() {
  local dir=$1 j=$1/probe.json
  [[ -s "$j" ]] || return 0
  local get lat
  get() { grep -o "\"$1\": [^,}]*" "$j" | head -1 | sed 's/.*: //'; }
  lat() { grep -o "\"latency_ms\": {[^}]*}" "$j" | grep -o "\"$1\": [^,}]*" | sed 's/.*: //'; }
  local frames_in published dropped
  frames_in=$(get frames_in); published=$(get labels_received)
  local void; void=$(get labels_all_void)
  dropped=$((frames_in - published))
  local tck; tck=$(getconf CLK_TCK)
  local usage
  usage=$(awk -v s="$(cat "$dir/start_ms")" -v e="$(cat "$dir/end_ms")" -v tck="$tck" '
    { if ($1 <= s) { t0 = $1; c0 = $2; m0 = $4; o0 = $5 }
      if ($1 <= e) { t1 = $1; c1 = $2; m1 = $4; o1 = $5 }
      if ($3 > hwm) hwm = $3 }
    END { if (t1 > t0) printf "%.0f %.0f %.1f %.1f", 100 * (c1 - c0) / tck / ((t1 - t0) / 1000), hwm / 1024,
                              100 * (m1 - m0) / tck / ((t1 - t0) / 1000),
                              100 * (o1 - o0) / tck / ((t1 - t0) / 1000);
          else printf "? %.0f ? ?", hwm / 1024 }' "$dir/usage")
  local span; span=$(awk -v s="$(cat "$dir/start_ms")" -v e="$(cat "$dir/end_ms")" 'BEGIN { printf "%.1f", (e - s) / 1000 }')
  local rest=${usage#* }
  rest=${rest% *}
  echo "input_fps=$(get input_fps) output_fps=$(get output_fps) frames_in=$frames_in published=$published dropped=$dropped labelled=$((published - void)) p50=$(lat p50) p99=$(lat p99) max=$(lat max) cpu=${usage%% *} rss=${rest% *} map_cpu=${rest##* } obj_cpu=${usage##* } map_frames=$(get semantic_map_frames) map_skipped=$(get semantic_map_skipped) map_voxels=$(get semantic_map_voxels) obj_frames=$(get object_frames) obj_skipped=$(get object_frames_skipped) obj_candidates=$(get object_candidates) obj_named=$(get objects_named) obj_mapped=$(get mapped_objects) obj_maps=$(get object_map_publishes) span_s=$span"
}
val() { sed -n "s/.*\b$2=\([^ ]*\).*/\1/p" <<< "$1"; }
fmt1() { awk -v v="$1" 'BEGIN { if (v == "") print "-"; else printf "%.1f", v }'; }
fmt0() { awk -v v="$1" 'BEGIN { if (v == "") print "-"; else printf "%.0f", v }'; }

# --- the grid ------------------------------------------------------------------------------------
LOAD_BEFORE=$(cut -d' ' -f1-3 /proc/loadavg)
if [[ $TABLES_ONLY == 1 ]]; then
  LOAD_BEFORE="$(cat "$RESULTS/load-before" 2>/dev/null || echo "?")"
  COMMAND_LINE="$(cat "$RESULTS/command" 2>/dev/null || echo "$COMMAND_LINE")"
else
  echo "$LOAD_BEFORE" > "$RESULTS/load-before"
  echo "$COMMAND_LINE" > "$RESULTS/command"
fi
for ds in $DATASETS; do
  for rate in $RATES; do
    for mode in $MODES; do
      [[ $TABLES_ONLY == 1 ]] || run_one "$ds" "$rate" "$mode" || true
    done
  done
done

# --- highest NYU rate held without drops (threaded) ----------------------------------------------
held() {  # DIR -> 0 if no frame was dropped
  local f; f=$(figures "$1")
  [[ -n "$f" && "$(val "$f" dropped)" == 0 ]]
}
# NYU threaded rates measured so far, ascending.
nyu_rates() {
  local d
  for d in "$RESULTS"/nyu-*fps-threaded; do
    [[ -s "$d/probe.json" ]] || continue
    d=${d##*/nyu-}; echo "${d%fps-threaded}"
  done | sort -g
}
# Highest rate held below the lowest rate with drops, and that lowest rate.
bracket() {
  lo="" hi=""
  local r
  for r in $(nyu_rates); do
    if held "$RESULTS/nyu-${r}fps-threaded"; then
      [[ -z "$hi" ]] && lo=$r
    elif [[ -z "$hi" ]]; then
      hi=$r
    fi
  done
}
SEARCHED=""
if [[ " $DATASETS " == *" nyu "* && " $MODES " == *" threaded "* ]]; then
  bracket
  if [[ $SEARCH == 1 && $TABLES_ONLY == 0 && -n "$lo" && -n "$hi" ]]; then
    for _ in 1 2 3; do
      mid=$(awk -v a="$lo" -v b="$hi" 'BEGIN { m = int((a + b) + 0.5) / 2; printf "%g", m }')
      awk -v m="$mid" -v a="$lo" -v b="$hi" 'BEGIN { exit !(m > a && m < b) }' || break
      run_one nyu "$mid" threaded || true
      bracket
    done
  fi
  for r in $(nyu_rates); do
    [[ " $RATES " == *" $r "* ]] || SEARCHED="$SEARCHED $r"
  done
  HIGHEST_HELD=${lo:-none}
  FIRST_DROPPING=${hi:-none}
fi
LOAD_AFTER=$(cut -d' ' -f1-3 /proc/loadavg)
if [[ $TABLES_ONLY == 1 ]]; then
  LOAD_AFTER="$(cat "$RESULTS/load-after" 2>/dev/null || echo "?")"
else
  echo "$LOAD_AFTER" > "$RESULTS/load-after"
fi

# --- the Markdown fragment ----------------------------------------------------------------------
commit=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
git -C "$ROOT" diff --quiet HEAD 2>/dev/null || commit="$commit (with uncommitted changes)"
commit="$commit; date $(date -u +%Y-%m-%dT%H:%MZ)"
if [[ $TABLES_ONLY == 1 ]]; then
  commit="$(cat "$RESULTS/commit" 2>/dev/null || echo "$commit")"
else
  echo "$commit" > "$RESULTS/commit"
fi
cpu_model=$(awk -F': ' '/model name/ {print $2; exit}' /proc/cpuinfo)
mem_gb=$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)
{
  echo "## Daemon under replayed input (\`tests/bench/daemon_bench.sh\`)"
  echo
  echo "- Machine: $cpu_model, $(nproc) cores, $mem_gb GiB RAM, Linux $(uname -r)"
  echo "- Commit: $commit"
  echo "- Command: \`$COMMAND_LINE\` (build \`$BUILD\`), model \`$MODEL_NAME\`"
  echo "- Each run: ${DURATION} s of input from \`findmug-replay\` (frames looped, fresh seq/utime),"
  echo "  LCM udpm in a private network namespace; latency = label image received - frame received"
  echo "  (same host clock); dropped = frames in - label images out; CPU = daemon process CPU time /"
  echo "  wall time of the run (200 % = both cores); peak RSS = VmHWM. \"labelled\" = label images"
  echo "  with at least one labelled pixel: a frame without a ground plane (no camera mount given and"
  echo "  none found) is published all void after the geometry stages only, and costs far less."
  echo "- Load average (1/5/15 min) before: $LOAD_BEFORE, after: $LOAD_AFTER. Other jobs on the machine"
  echo "  inflate latency and lower fps; compare rows of one run, not across runs."
  echo
  echo "### Sustained rate, latency, drops, CPU and memory"
  echo
  echo "| data | input fps | mode | measured in fps | out fps | frames in | published | labelled | dropped | p50 ms | p99 ms | max ms | CPU % | peak RSS MB |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  for ds in $DATASETS; do
    for rate in $RATES $([[ $ds == nyu ]] && echo "$SEARCHED"); do
      for mode in $MODES; do
        dir="$RESULTS/$ds-${rate}fps-$mode"
        [[ -d "$dir" ]] || continue
        f=$(figures "$dir")
        [[ -n "$f" ]] || continue
        echo "| $ds | $rate | $mode | $(fmt1 "$(val "$f" input_fps)") | $(fmt1 "$(val "$f" output_fps)") | $(val "$f" frames_in) | $(val "$f" published) | $(val "$f" labelled) | $(val "$f" dropped) | $(fmt0 "$(val "$f" p50)") | $(fmt0 "$(val "$f" p99)") | $(fmt0 "$(val "$f" max)") | $(val "$f" cpu) | $(val "$f" rss) |"
      done
    done
  done
  map_rows=""
  for ds in $DATASETS; do
    for rate in $RATES $([[ $ds == nyu ]] && echo "$SEARCHED"); do
      for mode in $MODES; do
        f=$(figures "$RESULTS/$ds-${rate}fps-$mode")
        [[ -n "$f" && "$(val "$f" map_frames)" != "" && "$(val "$f" map_frames)" != 0 ]] || continue
        per_s=$(awk -v n="$(val "$f" map_frames)" -v t="$(val "$f" span_s)" 'BEGIN { if (t > 0) printf "%.1f", n / t; else print "-" }')
        map_rows+="| $ds | $rate | $mode | $(val "$f" map_frames) | $per_s | $(val "$f" map_skipped) | $(val "$f" map_cpu) | $(val "$f" map_voxels) |"$'\n'
      done
    done
  done
  if [[ -n "$map_rows" ]]; then
    echo
    echo "### Semantic map sink (daemon.semantic_map)"
    echo
    echo "Frames fused into the map (those with a ground plane and a robot pose), per second of the run,"
    echo "frames its queue dropped (the map fell behind; their labels went out all the same), the map"
    echo "thread's CPU (findmug-semmap, % of one core over the run) and the map's voxels at the end."
    echo
    echo "| data | input fps | mode | fused | fused per s | skipped | map thread CPU % | voxels |"
    echo "|---|---|---|---|---|---|---|---|"
    printf "%s" "$map_rows"
  fi
  obj_rows=""
  for ds in $DATASETS; do
    for rate in $RATES $([[ $ds == nyu ]] && echo "$SEARCHED"); do
      for mode in $MODES; do
        dir="$RESULTS/$ds-${rate}fps-$mode"
        f=$(figures "$dir")
        [[ -n "$f" && "$(val "$f" obj_frames)" != "" && "$(val "$f" obj_frames)" != 0 ]] || continue
        j="$dir/probe.json"
        stage_cell() {
          grep -o "{\"name\": \"$1\", \"p50_ms\": [0-9.]*, \"p95_ms\": [0-9.]*, \"max_ms\": [0-9.]*}" "$j" 2>/dev/null \
            | head -1 | awk -F'[:,}]' '{printf "%.1f / %.1f / %.1f", $4, $6, $8}'
        }
        cand=$(awk -v c="$(val "$f" obj_candidates)" -v n="$(val "$f" obj_frames)" -v s="$(val "$f" obj_skipped)" \
          'BEGIN { if (n - s > 0) printf "%.1f", c / (n - s); else print "-" }')
        obj_rows+="| $ds | $rate | $mode | $(val "$f" obj_frames) | $(val "$f" obj_skipped) | $cand | $(val "$f" obj_named) | $(val "$f" obj_mapped) | $(val "$f" obj_maps) | $(stage_cell objects) | $(stage_cell object_search) | $(val "$f" obj_cpu) |"$'\n'
      done
    done
  done
  if [[ -n "$obj_rows" ]]; then
    echo
    echo "### Object work (daemon.objects_dir, robot pose on)"
    echo
    echo "Frames handed to the object work and of them skipped (its queue dropped them: the labels"
    echo "went out all the same), candidates put to the matcher per frame it worked on, candidates"
    echo "named, objects in the map at the end, object maps published; the table-top object stage"
    echo "(\`objects\`, on the segmentation workers) and the object work per frame (\`object_search\`:"
    echo "matching, object map, publishing; on its own thread), ms p50 / p95 / max over the run; that"
    echo "thread's CPU (findmug-objects, % of one core over the run)."
    echo
    echo "| data | input fps | mode | frames | skipped | candidates / frame | named | mapped | maps out | objects stage ms | object work ms | object thread CPU % |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
    printf "%s" "$obj_rows"
  fi
  trace_rows=""
  for ds in $DATASETS; do
    for rate in $RATES $([[ $ds == nyu ]] && echo "$SEARCHED"); do
      t="$RESULTS/$ds-${rate}fps-threaded/frame-trace.csv"
      [[ -s "$t" ]] || continue
      trace_rows+="$(python3 "$ROOT/tests/bench/frame_trace_summary.py" "$t" --label "$ds $rate fps")"$'\n'
    done
  done
  if [[ -n "$trace_rows" ]]; then
    echo
    echo "### Where the latency goes (threaded, the daemon's frame trace), ms p50 / p99 / max (mean of the slowest 1 %)"
    echo
    echo "Per published frame (daemon.frame_trace_file): source = frame sent to taken by the daemon"
    echo "(transit and the source's queue), door = waiting in the prepare queue, prepare, segment_wait"
    echo "= waiting for a segmentation worker, segment, reorder = held so that frames leave in order,"
    echo "publish_wait = waiting for the publish thread, publish = the sinks; total = submit to published."
    echo
    echo "| run | frames | source | door | prepare | segment_wait | segment | reorder | publish_wait | publish | total |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    printf "%s" "$trace_rows"
  fi
  if [[ " $MODES " == *" threaded "* && " $MODES " == *" sequential "* ]]; then
    echo
    echo "### Gain from pipelining (same library, same input)"
    echo
    echo "| data | input fps | threaded out fps | sequential out fps | out fps ratio | threaded p50 ms | sequential p50 ms |"
    echo "|---|---|---|---|---|---|---|"
    for ds in $DATASETS; do
      for rate in $RATES; do
        t=$(figures "$RESULTS/$ds-${rate}fps-threaded"); s=$(figures "$RESULTS/$ds-${rate}fps-sequential")
        [[ -n "$t" && -n "$s" ]] || continue
        ratio=$(awk -v a="$(val "$t" output_fps)" -v b="$(val "$s" output_fps)" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }')
        echo "| $ds | $rate | $(fmt1 "$(val "$t" output_fps)") | $(fmt1 "$(val "$s" output_fps)") | $ratio | $(fmt0 "$(val "$t" p50)") | $(fmt0 "$(val "$s" p50)") |"
      done
    done
  fi
  echo
  echo "### Time per stage (threaded, lowest input rate: no queueing), ms p50 / p95 / max"
  echo
  low=$(tr ' ' '\n' <<< "$RATES" | sort -g | head -1)
  stages="prepare segment publish object_search cloud normals ground oversegmentation features forest mrf labels tables objects total"
  header="| stage |"; rule="|---|"
  for ds in $DATASETS; do header="$header $ds |"; rule="$rule---|"; done
  echo "$header"; echo "$rule"
  for st in $stages; do
    row="| $st |"
    for ds in $DATASETS; do
      j="$RESULTS/$ds-${low}fps-threaded/probe.json"
      cell=$(grep -o "{\"name\": \"$st\", \"p50_ms\": [0-9.]*, \"p95_ms\": [0-9.]*, \"max_ms\": [0-9.]*}" "$j" 2>/dev/null \
        | head -1 | awk -F'[:,}]' '{printf "%.0f / %.0f / %.0f", $4, $6, $8}')
      row="$row ${cell:--} |"
    done
    echo "$row"
  done
  if [[ -n "${HIGHEST_HELD:-}" ]]; then
    echo
    echo "### Target: NYU frames at 5 fps, p99 latency <= 1 s, no drops (threaded)"
    echo
    f=$(figures "$RESULTS/nyu-5fps-threaded" || true)
    if [[ -n "$f" ]]; then
      verdict="NOT held"
      if [[ "$(val "$f" dropped)" == 0 ]] && awk -v p="$(val "$f" p99)" 'BEGIN { exit !(p <= 1000) }'; then verdict="held"; fi
      echo "- 5 fps: **$verdict** (dropped $(val "$f" dropped) of $(val "$f" frames_in), p99 $(fmt0 "$(val "$f" p99)") ms, output $(fmt1 "$(val "$f" output_fps)") fps)"
    fi
    echo "- Highest NYU input rate held without drops: **$HIGHEST_HELD fps** (first rate with drops: $FIRST_DROPPING fps; bisection runs:${SEARCHED:- none})"
  fi
  echo
  echo "Raw reports (JSON, latency histograms, logs): \`$RESULTS\`."
} > "$OUT"
log "wrote $OUT"
cat "$OUT"
