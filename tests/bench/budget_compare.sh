#!/usr/bin/env bash
# budget_compare.sh — issue 13's before/after: 30 fps NYU and synthetic input,
# one build against another, in one run, interleaved per data set:
#   base        the older build (threaded, its defaults)
#   new         this build, threaded, its defaults (daemon.max_cpu_cores 0)
#   new-1core   this build with daemon.max_cpu_cores=1 (every stage on one thread)
#
#   tests/bench/budget_compare.sh BASE_BUILD_DIR [--duration 15] [--rate 30] [--out DIR] [--model FMF]
#       [--synth-model FMF] [--set KEY=VALUE]...
#
# --model: the forest every row runs. Without it, daemon_bench.sh's default:
# the committed models/findmug.fmf with the settings it was trained with
# (models/README.md). An older base build may not read the current model
# format; give it a model it reads (e.g. that commit's models/findmug.fmf, a
# format-2 forest without region features), and every row runs that model.
# --synth-model: the forest of the synthetic rows instead, trained with region
# and scene features like the committed ones (they get
# features.regions=true and features.scene=true): models/findmug-nyu-synth.fmf
# is the model for rendered scenes, as the README demo runs it. The NYU-only
# model labels 39 % of the rendered pixels wrong, many of them table, and
# the table stage then measures surfaces that are no tables (perf-log §9w).
# --set: extra daemon settings for every row (both builds).
#
# Each configuration is one tests/bench/daemon_bench.sh run (threaded mode,
# no rate search); the table of the three goes to DIR/compare.md.
# Host speed: this VM's speed drifts by up to 30-40 % within minutes
# (perf-log §9w, 9x), which moves a row's CPU % as much as a build does.
# Right before each row, this build's frame_cpu times the 31 NYU frames on
# CPU 0 (one pass, findmug.fmf); the median CPU ms per frame goes in the
# "host ref ms" column. The same program on the same frames every time, so
# it changes only with the host: rows with a higher figure ran on a slower
# host.
# --tables-only rewrites compare.md from an existing --out directory.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BASE=$1; shift
TABLES_ONLY=0 DURATION=15 RATE=30 MODEL="" SYNTH_MODEL="" SETS=() OUT="$ROOT/build/bench-results/budget-$(date -u +%Y%m%dT%H%M%SZ)"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --duration) DURATION=$2; shift 2 ;;
    --rate) RATE=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --model) MODEL=$2; shift 2 ;;
    --synth-model) SYNTH_MODEL=$2; shift 2 ;;
    --set) SETS+=(--set "$2"); shift 2 ;;
    --tables-only) TABLES_ONLY=1; shift ;;
    *) echo "budget_compare: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
BENCH="$ROOT/tests/bench/daemon_bench.sh"
# The host reference of the next row into FILE ("-" if frame_cpu cannot run,
# e.g. without the NYU data: the column is then empty, the runs go on).
host_ref() {
  local ms
  ms=$(taskset -c 0 "$ROOT/build/tests/bench/frame_cpu" --model "$ROOT/models/findmug.fmf" \
         --passes 1 --set features.regions=true --set features.scene=true --set learner.classes=nyu13 \
         --set features.objects=true --set features.objects_columns=relations --heap-keep-mb 256 \
         2>/dev/null | awk -F'|' '/\*\*total\*\*/ { gsub(/[* ]/, "", $3); print $3 }') || true
  echo "${ms:--}" > "$1"
}
[[ $TABLES_ONLY == 1 ]] || echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)" > "$OUT/load"
DATASETS=${DATASETS:-nyu synth}
for ds in $DATASETS; do
  [[ $TABLES_ONLY == 1 ]] && break
  MODEL_ARGS=()
  [[ -n "$MODEL" ]] && MODEL_ARGS=(--model "$MODEL")
  if [[ $ds == synth && -n "$SYNTH_MODEL" ]]; then
    MODEL_ARGS=(--model "$SYNTH_MODEL" --set features.regions=true --set features.scene=true)
  fi
  host_ref "$OUT/base-$ds.host"
  "$BENCH" --build-dir "$BASE" --datasets "$ds" --rates "$RATE" --modes threaded --no-search \
    --duration "$DURATION" "${MODEL_ARGS[@]+"${MODEL_ARGS[@]}"}" "${SETS[@]+"${SETS[@]}"}" --results "$OUT/base-$ds" --out "$OUT/base-$ds.md"
  host_ref "$OUT/new-$ds.host"
  "$BENCH" --build-dir "$ROOT/build" --datasets "$ds" --rates "$RATE" --modes threaded --no-search \
    --duration "$DURATION" "${MODEL_ARGS[@]+"${MODEL_ARGS[@]}"}" "${SETS[@]+"${SETS[@]}"}" --results "$OUT/new-$ds" --out "$OUT/new-$ds.md"
  host_ref "$OUT/new-1core-$ds.host"
  "$BENCH" --build-dir "$ROOT/build" --datasets "$ds" --rates "$RATE" --modes threaded --no-search \
    --duration "$DURATION" "${MODEL_ARGS[@]+"${MODEL_ARGS[@]}"}" "${SETS[@]+"${SETS[@]}"}" --results "$OUT/new-1core-$ds" \
    --out "$OUT/new-1core-$ds.md" --set daemon.max_cpu_cores=1
done
[[ $TABLES_ONLY == 1 ]] || echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$OUT/load"
{
  echo "| data | build | input fps | out fps | frames in | published | dropped | p50 ms | p99 ms | max ms | CPU % | CPU ms per published frame | peak RSS MB | host ref ms |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  for ds in nyu synth; do
    for b in base new new-1core; do
      [[ -f "$OUT/$b-$ds.md" ]] || continue
      row=$(grep "^| $ds | $RATE | threaded" "$OUT/$b-$ds.md" || true)
      # daemon_bench's columns: data rate mode in out frames published labelled dropped p50 p99 max cpu rss
      host=-
      [[ -f "$OUT/$b-$ds.host" ]] && host=$(cat "$OUT/$b-$ds.host")
      awk -F'|' -v b="$b" -v ds="$ds" -v host="$host" 'NF > 10 {
        per = ($6 + 0 > 0) ? sprintf("%.1f", 10 * $14 / $6) : "-";
        printf "| %s | %s |%s|%s|%s|%s|%s|%s|%s|%s|%s| %s |%s| %s |\n", ds, b, $5, $6, $7, $8, $10, $11, $12, $13, $14, per, $15, host }' <<< "$row"
    done
  done
  echo
  for ds in nyu synth; do
    [[ -f "$OUT/new-$ds/model-name" ]] && echo "$ds rows: model $(cat "$OUT/new-$ds/model-name")"
  done
  cat "$OUT/load"
} > "$OUT/compare.md"
cat "$OUT/compare.md"
