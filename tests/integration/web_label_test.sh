#!/usr/bin/env bash
# web_label_test.sh — findmug-web's Label page in headless chromium: label one real NYU
# frame and check the written label8/ PNG pixel for pixel. SCRIPT (in clients/web/test):
#   label_test.mjs        clicks, keys, undo, save, 409 on a newer file (the default)
#   label_tools_test.mjs  prediction, drag, region fill, undo/redo, the draft, save
#   draft_test.mjs        findmug-web killed after a stroke and restarted: the draft is
#                         offered and restored; a bad draft file is refused with a message
#
#   web_label_test.sh --web B [--script SCRIPT] [--frame NAME] [--out DIR]
#
# The frame (rgb + depth, no labels) is copied into a scratch dataset folder; findmug-web
# serves it on 127.0.0.1 inside a private network namespace, with the shipped model
# (models/findmug.fmf and the settings it was trained with, models/README.md) for the
# prediction. Exit 0 pass, 1 fail, 77 skipped (chromium, node, puppeteer-core or data
# missing; failures under CI=true).
set -euo pipefail
WEB="" OUT="" SCRIPT=label_test.mjs FRAME=0001
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --web) WEB=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --script) SCRIPT=$2; shift 2 ;;
    --frame) FRAME=$2; shift 2 ;;
    *) echo "web_label_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ -x "$WEB" ]] || { echo "web_label_test: --web must name findmug-web" >&2; exit 2; }
SKIP_NAME="web_label_test"
source "$SOURCE_DIR/tests/support/skip.sh"
source "$SOURCE_DIR/tests/support/web_test.sh"
web_test_needs_browser
DATA_DIR="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}"
NYU="$DATA_DIR/nyuv2_labeled"
[[ -f "$NYU/rgb/$FRAME.png" ]] || skip "NYU frames missing at $NYU (set FINDMUG_DATA)"
ROTATIONS="$DATA_DIR/nyuv2_meta/camera_rotations_NYU.txt"
[[ -f "$ROTATIONS" ]] || skip "NYU gravity rotations missing at $ROTATIONS"
web_test_enter_netns "${ARGS[@]}"

WORK=$(mktemp -d /tmp/findmug-web-label.XXXXXX)
[[ -n "$OUT" ]] || OUT=$WORK
mkdir -p "$OUT" "$WORK/data/rgb" "$WORK/data/depth"
cp "$NYU/rgb/$FRAME.png" "$WORK/data/rgb/"
cp "$NYU/depth/$FRAME.png" "$WORK/data/depth/"
WEB_CMD=("$WEB" --lcm-url memq:// --port 18091 --static-dir "$SOURCE_DIR/clients/web/static"
         --data "$WORK/data" --model "$SOURCE_DIR/models/findmug.fmf" --nyu-rotations "$ROTATIONS"
         --set ground.source=gravity --set features.regions=true --set features.scene=true
         --set learner.classes=nyu13 --set features.objects=true --set features.objects_columns=relations)
if [[ "$SCRIPT" == draft_test.mjs ]]; then
  # It starts (and kills) findmug-web itself.
  if ! node "$SOURCE_DIR/clients/web/test/draft_test.mjs" --url "http://127.0.0.1:18091/" \
       --data "$WORK/data" --frame "$FRAME" --out "$OUT" --log "$WORK/web.log" \
       --web-cmd "$(printf '%s\n' "${WEB_CMD[@]}")"; then
    echo "web_label_test: $SCRIPT FAILED" >&2
    tail -20 "$WORK/web.log" >&2
    rm -rf "$WORK"
    exit 1
  fi
  rm -rf "$WORK"
  echo "web_label_test: $SCRIPT passed"
  exit 0
fi
"${WEB_CMD[@]}" > "$WORK/web.log" 2>&1 &
web=$!
trap 'kill -TERM $web 2>/dev/null || true; wait $web 2>/dev/null || true; rm -rf "$WORK"' EXIT
web_test_wait_for_port 18091 "$web"
if ! node "$SOURCE_DIR/clients/web/test/$SCRIPT" --url "http://127.0.0.1:18091/" \
     --data "$WORK/data" --frame "$FRAME" --out "$OUT"; then
  echo "web_label_test: $SCRIPT FAILED" >&2
  tail -20 "$WORK/web.log" >&2
  exit 1
fi
echo "web_label_test: $SCRIPT passed"
