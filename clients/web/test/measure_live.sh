#!/usr/bin/env bash
# measure_live.sh — findmug-web's live view at a given label-image rate: updates per
# second on the page, publish-to-page delay, and findmug-web's CPU (docs/measurements/web.md).
#
#   measure_live.sh --findmugd B --web B [--fps 30] [--record-s 45] [--measure-s 6]
#
# 1. Records findmugd's output (labels with the camera image, tables, status) over
#    nyuv2_labeled at 4 frames/s for RECORD_S seconds into an LCM log (file://).
# 2. In a private network namespace, lcm-logplayer plays the log on udpm at FPS/4 times
#    its speed (FPS label images a second), findmug-web listens, and live_test.mjs
#    (headless chromium) reports the page's updates per second and delays while
#    findmug-web's CPU time is read from /proc.
set -euo pipefail
FINDMUGD="" WEB="" FPS=30 RECORD_S=45 MEASURE_S=6
SOURCE_DIR="$(cd "$(dirname "$0")/../../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --findmugd) FINDMUGD=$2; shift 2 ;;
    --web) WEB=$2; shift 2 ;;
    --fps) FPS=$2; shift 2 ;;
    --record-s) RECORD_S=$2; shift 2 ;;
    --measure-s) MEASURE_S=$2; shift 2 ;;
    *) echo "measure_live: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
if [[ "${FINDMUG_WEB_NETNS:-}" != 1 ]]; then
  exec unshare --net env FINDMUG_WEB_NETNS=1 bash "$0" "${ARGS[@]}"
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"
NYU="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}/nyuv2_labeled"
WORK=$(mktemp -d /tmp/findmug-web-measure.XXXXXX)
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$WORK"' EXIT

"$FINDMUGD" --source "dataset:$NYU?rate_hz=4&loop=1" --lcm-url "file://$WORK/out.lcm?mode=w" \
  --model "$SOURCE_DIR/models/findmug.fmf" --set features.regions=true --set features.scene=true \
  --set learner.classes=nyu13 --set features.objects=true --set features.objects_columns=relations \
  --set daemon.publish_color=true --set daemon.status_period_s=0.5 --log-level warn \
  > "$WORK/findmugd.log" 2>&1 &
daemon=$!
sleep "$RECORD_S"
kill -TERM "$daemon"; wait "$daemon" || true
echo "measure_live: recorded $(stat -c %s "$WORK/out.lcm") bytes"

"$WEB" --lcm-url "$URL" --port 18089 --static-dir "$SOURCE_DIR/clients/web/static" \
  > "$WORK/web.log" 2>&1 &
web=$!
sleep 1
speed=$(awk -v f="$FPS" 'BEGIN { print f / 4 }')
# Played again and again, so that the page sees FPS label images a second throughout.
(while true; do lcm-logplayer -s "$speed" --lcm-url "$URL" "$WORK/out.lcm" > /dev/null 2>&1; done) &
player=$!
ticks() { awk '{print $14 + $15}' "/proc/$web/stat"; }
# The page needs a few frames and a table before it measures; CPU over the measurement.
t0=$(date +%s.%N); c0=$(ticks)
result=$(node "$SOURCE_DIR/clients/web/test/live_test.mjs" --url "http://127.0.0.1:18089/" \
         --out "$WORK" --measure-s "$MEASURE_S") || { tail "$WORK/web.log"; exit 1; }
t1=$(date +%s.%N); c1=$(ticks)
kill "$player" 2>/dev/null || true
echo "measure_live: fps $FPS: $result"
awk -v a="$c0" -v b="$c1" -v s="$t0" -v e="$t1" -v hz="$(getconf CLK_TCK)" \
  'BEGIN { printf "measure_live: findmug-web CPU %.3f cores over %.1f s (page open)\n", (b - a) / hz / (e - s), e - s }'
