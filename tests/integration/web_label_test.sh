#!/usr/bin/env bash
# web_label_test.sh — findmug-web's Label page in headless chromium: label one real NYU
# frame by clicks and check the written label8/ PNG pixel for pixel
# (clients/web/test/label_test.mjs).
#
#   web_label_test.sh --web B [--out DIR]
#
# The frame (rgb + depth, no labels) is copied into a scratch dataset folder; findmug-web
# serves it on 127.0.0.1 inside a private network namespace. Exit 0 pass, 1 fail, 77
# skipped (chromium, node, puppeteer-core or data missing; failures under CI=true).
set -euo pipefail
WEB="" OUT=""
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --web) WEB=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "web_label_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ -x "$WEB" ]] || { echo "web_label_test: --web must name findmug-web" >&2; exit 2; }
SKIP_NAME="web_label_test"
source "$SOURCE_DIR/tests/support/skip.sh"
need_tools node unshare ip
[[ -x "${FINDMUG_CHROMIUM:-/usr/bin/chromium}" ]] || skip "chromium not installed (scripts/install-deps.sh)"
[[ -d "$SOURCE_DIR/clients/web/test/node_modules/puppeteer-core" ]] ||
  skip "puppeteer-core not installed (scripts/install-deps.sh runs npm ci in clients/web/test)"
NYU="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}/nyuv2_labeled"
[[ -f "$NYU/rgb/0001.png" ]] || skip "NYU frames missing at $NYU (set FINDMUG_DATA)"
if [[ "${FINDMUG_WEB_NETNS:-}" != 1 ]]; then
  ns=(unshare --net)
  [[ $EUID -eq 0 ]] || ns=(unshare --net --map-root-user)
  exec "${ns[@]}" env FINDMUG_WEB_NETNS=1 bash "$0" "${ARGS[@]}"
fi
ip link set lo up

WORK=$(mktemp -d /tmp/findmug-web-label.XXXXXX)
[[ -n "$OUT" ]] || OUT=$WORK
mkdir -p "$OUT" "$WORK/data/rgb" "$WORK/data/depth"
cp "$NYU/rgb/0001.png" "$WORK/data/rgb/"
cp "$NYU/depth/0001.png" "$WORK/data/depth/"
"$WEB" --lcm-url memq:// --port 18091 --static-dir "$SOURCE_DIR/clients/web/static" \
  --data "$WORK/data" > "$WORK/web.log" 2>&1 &
web=$!
trap 'kill -TERM $web 2>/dev/null || true; wait $web 2>/dev/null || true; rm -rf "$WORK"' EXIT
for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/18091) 2>/dev/null && break; sleep 0.1; done
if ! node "$SOURCE_DIR/clients/web/test/label_test.mjs" --url "http://127.0.0.1:18091/" \
     --data "$WORK/data" --frame 0001 --out "$OUT"; then
  echo "web_label_test: FAILED" >&2
  tail -20 "$WORK/web.log" >&2
  exit 1
fi
echo "web_label_test: passed"
