#!/usr/bin/env bash
# web_teach_test.sh — "teach my mug" on findmug-web's live page and find it, in headless
# chromium, over a running findmugd on the demo's synthetic apartment.
#
#   web_teach_test.sh --findmugd B --web B --synth B --replay B --nav B [--out DIR]
#
# In a private network namespace (only loopback; udpm multicast routed on it):
# findmug-synth renders the demo's apartment (scripts/demo.sh: seed 7, here 60 frames at
# 5 fps); findmug-replay publishes it in a loop on udpm, with a robot standing at the map
# origin (--robot-pose); findmugd (the demo's model and settings, a folder for taught
# objects, the camera image in the label images) labels it, takes commands and poses from
# the same bus; findmug-web serves 127.0.0.1:PORT. clients/web/test/teach_test.mjs
# (puppeteer-core driving /usr/bin/chromium) waits for the mug among the drawn candidates,
# names it "mug" and clicks it, waits for "taught mug (1 view)", asks find "mug" and waits
# for "seen ... on table"; saves OUT/teach.png. Then checks the model file findmugd wrote,
# and findmug-nav-client's --find (answered: mug seen) and --teach (a frame not held:
# refused, saying so) on the same bus.
#
# Exit: 0 pass, 1 fail, 77 skipped (chromium, node or puppeteer-core missing; under
# CI=true those fail instead).
set -euo pipefail

FINDMUGD="" WEB="" SYNTH="" REPLAY="" NAV="" OUT=""
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --findmugd) FINDMUGD=$2; shift 2 ;;
    --web) WEB=$2; shift 2 ;;
    --synth) SYNTH=$2; shift 2 ;;
    --replay) REPLAY=$2; shift 2 ;;
    --nav) NAV=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    *) echo "web_teach_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
for tool in "$FINDMUGD" "$WEB" "$SYNTH" "$REPLAY" "$NAV"; do
  [[ -x "$tool" ]] || { echo "web_teach_test: --findmugd, --web, --synth, --replay and --nav must name executables" >&2; exit 2; }
done

SKIP_NAME="web_teach_test"
source "$SOURCE_DIR/tests/support/skip.sh"
source "$SOURCE_DIR/tests/support/web_test.sh"
web_test_needs_browser

# --- into a private network namespace: nothing can leave the machine ----------------
web_test_enter_netns "${ARGS[@]}"
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
PORT=18089

web_test_workdir findmug-web-teach-test

"$SYNTH" --seed 7 --frames 60 --fps 5 --out "$WORK/apartment" > "$WORK/synth.log" 2>&1 ||
  fail "findmug-synth failed"
mkdir "$WORK/objects"
# scripts/demo.sh's model and settings; the robot's pose from the replay (map origin).
"$FINDMUGD" --config "$SOURCE_DIR/daemon/findmugd.yaml" \
  --model "$SOURCE_DIR/models/findmug-nyu-synth.fmf" \
  --set learner.classes=labels --set features.objects=false --set mrf.pairwise=potts \
  --source "lcm:FINDMUG_RGBD?url=$URL" --lcm-url "$URL" \
  --set daemon.objects_dir="$WORK/objects" --set daemon.publish_color=true \
  --set daemon.status_period_s=0.5 --log-level info > "$WORK/findmugd.log" 2>&1 &
pids+=($!)
"$WEB" --lcm-url "$URL" --port "$PORT" --static-dir "$SOURCE_DIR/clients/web/static" \
  > "$WORK/findmug-web.log" 2>&1 &
web_pid=$!
pids+=($web_pid)
web_test_wait_for_port "$PORT" "$web_pid"
"$REPLAY" --source "dataset:$WORK/apartment" --rate 5 --duration 600 --robot-pose 0,0,0 \
  --url "$URL" > "$WORK/replay.log" 2>&1 &
pids+=($!)

result=$(node "$SOURCE_DIR/clients/web/test/teach_test.mjs" --url "http://127.0.0.1:$PORT/" \
         --out "$OUT") || fail "the page check failed"
echo "web_teach_test: $result"
[[ -s "$OUT/teach.png" ]] || fail "no screenshot"
# What the click made: the daemon's model file, one view, named mug.
[[ -s "$WORK/objects/mug.fmo" ]] || fail "no $WORK/objects/mug.fmo"
grep -q "taught object loaded: .*mug.fmo" "$WORK/findmugd.log" || fail "findmugd never loaded mug.fmo"
# The navigation client's side of the same loop.
found=$("$NAV" --lcm-url "$URL" --find mug --timeout 20) || fail "findmug-nav-client --find mug: $found"
[[ "$found" == *"mug seen at"* ]] || fail "findmug-nav-client --find mug: $found"
echo "web_teach_test: findmug-nav-client --find mug: $(head -n1 <<< "$found")"
rc=0
refused=$("$NAV" --lcm-url "$URL" --teach mug 999999999 0 --timeout 20) || rc=$?
[[ $rc -eq 4 && "$refused" == *"frame seq 999999999 is not held"* ]] ||
  fail "findmug-nav-client --teach mug 999999999 0: exit $rc, '$refused'"
echo "web_teach_test: findmug-nav-client --teach mug 999999999 0: $refused"
echo "web_teach_test: screenshot $OUT/teach.png"
echo "web_teach_test: passed"
