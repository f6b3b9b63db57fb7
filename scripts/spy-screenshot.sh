#!/bin/bash
# spy-screenshot.sh — a PNG of findmug-spy showing findmug messages being replayed.
#
#   scripts/spy-screenshot.sh [BUILD_DIR] [OUT.png]
#
# 1. findmug-grab turns a few NYU dataset frames into an LCM log (file://, no network);
# 2. inside a private network namespace (needs root: unshare --net), with only
#    loopback up and multicast routed to it, Xvfb starts, findmug-spy listens
#    on udpm (ttl=0) and lcm-logplayer replays the log in a loop;
# 3. the spy window is captured with xwd and converted to PNG.
# The namespace guarantees no packet can leave the machine: it has no other interface.
#
# OPEN_VIEWER=1 (default; 0 to skip) double-clicks the FINDMUG_RGBD row (java.awt.Robot via
# jshell) to open the decoded-message view as well.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-${FINDMUG_BUILD_DIR:-$repo/build}}"
out="${2:-$PWD/findmug-spy.png}"
data="${FINDMUG_DATA:-$repo/../shared/data}"
grab="$build/tools/findmug-grab"
spy="$build/clients/findmug-spy"

for f in "$grab" "$spy" "$build/lcmtypes/findmug_lcmtypes.jar"; do
  [[ -e "$f" ]] || { echo "spy-screenshot: $f missing (build findmug-grab, findmug_lcmtypes_jar)" >&2; exit 1; }
done
[[ -d "$data/nyuv2_labeled" ]] || { echo "spy-screenshot: no $data/nyuv2_labeled (set FINDMUG_DATA)" >&2; exit 1; }
for tool in unshare ip Xvfb xwd convert lcm-logplayer java; do
  command -v "$tool" >/dev/null || { echo "spy-screenshot: $tool not installed" >&2; exit 1; }
done
[[ $(id -u) -eq 0 ]] || { echo "spy-screenshot: needs root for unshare --net" >&2; exit 1; }

work="$(mktemp -d /tmp/findmug-spy.XXXXXX)"
trap 'rm -rf "$work"' EXIT

"$grab" --source "dataset:$data/nyuv2_labeled?rate_hz=10" --count 10 \
        --url "file://$work/frames.lcm?mode=w" >"$work/grab.log" 2>&1 \
  || { cat "$work/grab.log" >&2; exit 1; }

export work spy out
unshare --net bash -euo pipefail -c '
  ip link set lo up
  ip link set lo multicast on   # loopback has no MULTICAST flag by default
  ip route add 224.0.0.0/4 dev lo
  url="udpm://239.255.76.67:7667?ttl=0"
  # A display number nobody uses (lock files live in the shared /tmp).
  n=90
  while [[ -e /tmp/.X$n-lock || -e /tmp/.X11-unix/X$n ]]; do n=$((n + 1)); done
  display=":$n"
  Xvfb "$display" -screen 0 1280x800x24 -nolisten tcp >"$work/xvfb.log" 2>&1 &
  xvfb=$!
  pids="$xvfb"
  cleanup() { for p in $pids; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
  trap cleanup EXIT
  for _ in $(seq 50); do [[ -e /tmp/.X11-unix/X$n ]] && break; sleep 0.1; done
  export DISPLAY="$display"
  "$spy" --lcm-url="$url" >"$work/spy.log" 2>&1 &
  pids="$! $pids"
  sleep 4   # JVM start and Spy window
  # Replay in a loop so that rates stay up while we look.
  ( while true; do lcm-logplayer --lcm-url="$url" "$work/frames.lcm" >/dev/null 2>&1; done ) &
  pids="$! $pids"
  sleep 5
  if [[ "${OPEN_VIEWER:-1}" == 1 ]]; then
    printf "%s\n" "import java.awt.*; import java.awt.event.*;" \
      "Robot r = new Robot(); r.mouseMove(80, 27); r.delay(300);" \
      "for (int i = 0; i < 2; i++) { r.mousePress(InputEvent.BUTTON1_DOWN_MASK); r.mouseRelease(InputEvent.BUTTON1_DOWN_MASK); r.delay(80); }" \
      "/exit" > "$work/click.jsh"
    jshell -q "$work/click.jsh" >/dev/null 2>&1 || true
    sleep 3
  fi
  xwd -root -silent -display "$display" > "$work/screen.xwd"
  convert "xwd:$work/screen.xwd" "$out"
' || { echo "spy-screenshot: failed; logs:" >&2; tail -n 20 "$work"/*.log >&2 || true; exit 1; }
echo "spy-screenshot: wrote $out"
