#!/usr/bin/env bash
# web_browser_test.sh — findmug-web's live page in headless chromium, over a running
# findmugd that replays real NYU frames.
#
#   web_browser_test.sh --findmugd B --web B [--spy-log B] [--out DIR] [--rate HZ]
#                       [--measure-s N]
#
# In a private network namespace (only loopback; udpm multicast routed on it):
# findmugd reads dataset:nyuv2_labeled (looping, RATE frames/s) and publishes labels
# with the camera image (daemon.publish_color) on udpm; findmug-web subscribes to the
# same bus and serves 127.0.0.1:PORT; clients/web/test/live_test.mjs (puppeteer-core
# driving /usr/bin/chromium) checks that the label overlay updates and a table hull is
# drawn, saves OUT/live.png, and reports updates per second and delays. The CPU time
# findmug-web took during the measurement is read from /proc. With --spy-log (the
# findmug-test-spy-log program), live_test.mjs then replays that log's FINDMUG_SEMANTIC_MAP
# and FINDMUG_TABLE_MAP messages into the bus (lcm-logplayer) and checks the map panel
# draws the semantic map under the table (OUT/live-map.png).
#
# Exit: 0 pass, 1 fail, 77 skipped (chromium, node, puppeteer-core or data missing;
# under CI=true those fail instead).
set -euo pipefail

FINDMUGD="" WEB="" SPY_LOG="" OUT="" RATE=5 MEASURE_S=10
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --findmugd) FINDMUGD=$2; shift 2 ;;
    --web) WEB=$2; shift 2 ;;
    --spy-log) SPY_LOG=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --rate) RATE=$2; shift 2 ;;
    --measure-s) MEASURE_S=$2; shift 2 ;;
    -h|--help) sed -n '2,24p' "$0"; exit 0 ;;
    *) echo "web_browser_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ -x "$FINDMUGD" && -x "$WEB" ]] || { echo "web_browser_test: --findmugd and --web must name executables" >&2; exit 2; }

SKIP_NAME="web_browser_test"
source "$SOURCE_DIR/tests/support/skip.sh"
source "$SOURCE_DIR/tests/support/web_test.sh"
web_test_needs_browser
TEST_DIR="$SOURCE_DIR/clients/web/test"
DATA_ROOT="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}"
NYU="$DATA_ROOT/nyuv2_labeled"
[[ -d "$NYU/rgb" ]] || skip "NYU frames missing at $NYU (set FINDMUG_DATA)"

# --- into a private network namespace: nothing can leave the machine ----------------
web_test_enter_netns "${ARGS[@]}"
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
PORT=18088

web_test_workdir findmug-web-test

MODEL="$SOURCE_DIR/models/findmug.fmf"
[[ -f "$MODEL" ]] || fail "no model at $MODEL"
# The committed model's settings: region, scene and object features, NYU-13 classes
# (models/README.md).
"$FINDMUGD" --source "dataset:$NYU?rate_hz=$RATE&loop=1" --lcm-url "$URL" --model "$MODEL" \
  --set features.regions=true --set features.scene=true --set learner.classes=nyu13 \
  --set features.objects=true --set features.objects_columns=relations \
  --set daemon.publish_color=true \
  --set daemon.status_period_s=0.5 --log-level warn > "$WORK/findmugd.log" 2>&1 &
pids+=($!)
"$WEB" --lcm-url "$URL" --port "$PORT" --static-dir "$SOURCE_DIR/clients/web/static" \
  --data "$NYU" > "$WORK/findmug-web.log" 2>&1 &
web_pid=$!
pids+=($web_pid)
web_test_wait_for_port "$PORT" "$web_pid"

map_args=()
if [[ -n "$SPY_LOG" ]]; then
  need_tools lcm-logplayer
  "$SPY_LOG" "$WORK/map.lcm" || fail "findmug-test-spy-log failed"
  # Replayed every second until the page has drawn it (live_test.mjs ends the loop).
  map_args=(--map-log-cmd "while true; do lcm-logplayer -e '^FINDMUG_(SEMANTIC_MAP|TABLE_MAP)\$' -l '$URL' '$WORK/map.lcm'; sleep 1; done")
fi

cpu_ticks() { awk '{print $14 + $15}' "/proc/$web_pid/stat"; }
ticks_before=$(cpu_ticks)
t_before=$(date +%s.%N)
result=$(node "$TEST_DIR/live_test.mjs" --url "http://127.0.0.1:$PORT/" --out "$OUT" \
         --measure-s "$MEASURE_S" "${map_args[@]+"${map_args[@]}"}") || fail "the page check failed"
ticks_after=$(cpu_ticks)
t_after=$(date +%s.%N)
kill -0 "$web_pid" 2>/dev/null || fail "findmug-web died"
cpu=$(awk -v a="$ticks_before" -v b="$ticks_after" -v s="$t_before" -v e="$t_after" \
      -v hz="$(getconf CLK_TCK)" 'BEGIN { printf "%.3f", (b - a) / hz / (e - s) }')
echo "web_browser_test: $result"
echo "web_browser_test: findmug-web CPU over the page test: $cpu cores; screenshot $OUT/live.png"
[[ -s "$OUT/live.png" ]] || fail "no screenshot"
echo "web_browser_test: passed"
