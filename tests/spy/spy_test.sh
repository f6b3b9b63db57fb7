#!/usr/bin/env bash
# spy_test.sh BUILD_DIR SOURCE_DIR — findmug-spy decodes every findmug channel.
#
# A log with one message of every findmug type on its channel (findmug-test-spy-log) is
# replayed in a loop by lcm-logplayer on udpm inside a private network namespace (only
# loopback, multicast routed to it: no packet can leave), while lcm-spy runs under Xvfb
# with findmug-spy's class path. SpyProbe.java starts the spy in its JVM and prints the
# spy's channel table; every findmug channel must be listed with its findmug type (a
# channel whose type the spy cannot decode shows no type and counts undecodable messages).
# Needs root (unshare --net).
# Exit 77 = skipped (not under CI=true). SPY_TEST_CLASSPATH_OVERRIDE=CP runs the spy with
# another class path (without findmug_lcmtypes.jar the test fails, as it should).
set -euo pipefail

build=$(cd "${1:?build dir}" && pwd)
source_dir=$(cd "${2:?source dir}" && pwd)

SKIP_NAME="spy test"
source "$source_dir/tests/support/skip.sh"
need_root "unshare --net"
need_tools unshare ip Xvfb java lcm-logplayer
classpath=${SPY_TEST_CLASSPATH_OVERRIDE:-$("$build/clients/findmug-spy" --print-classpath)} || skip "findmug-spy has no class path"

work=$(mktemp -d /tmp/findmug-spy-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
"$build/tests/spy/findmug-test-spy-log" "$work/all.lcm"
cp "$source_dir/tests/spy/SpyProbe.java" "$work/"

export work classpath
unshare --net bash -euo pipefail -c '
  ip link set lo up
  ip link set lo multicast on
  ip route add 224.0.0.0/4 dev lo
  url="udpm://239.255.76.67:7667?ttl=0"
  n=90
  while [[ -e /tmp/.X$n-lock || -e /tmp/.X11-unix/X$n ]]; do n=$((n + 1)); done
  Xvfb ":$n" -screen 0 1280x800x24 -nolisten tcp >"$work/xvfb.log" 2>&1 &
  pids=$!
  cleanup() { for p in $pids; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
  trap cleanup EXIT
  for _ in $(seq 50); do [[ -e /tmp/.X11-unix/X$n ]] && break; sleep 0.1; done
  export DISPLAY=":$n"
  ( while true; do lcm-logplayer --lcm-url="$url" "$work/all.lcm" >/dev/null 2>&1; sleep 0.2; done ) &
  pids="$! $pids"
  cd "$work"
  # The spy subscribes once its window is up; 8 s cover JVM start plus several replays.
  java -Djava.net.preferIPv4Stack=true -cp "$classpath" SpyProbe.java 8000 --lcm-url="$url" \
    >"$work/table.txt" 2>"$work/java.log"
' || { echo "spy test: run failed"; tail -n 20 "$work"/*.log; exit 1; }

echo "== lcm-spy's channel table"
cat "$work/table.txt"
status=0
for pair in FINDMUG_RGBD:rgbd_frame_t FINDMUG_LABELS:label_image_t FINDMUG_TABLES:tables_t \
            FINDMUG_OBJECTS:objects_t FINDMUG_OBJECT_MAP:objects_t \
            FINDMUG_TABLE_MAP:tables_t FINDMUG_STATUS:status_t FINDMUG_ROBOT_POSE:robot_pose_t \
            FINDMUG_SEMANTIC_MAP:semantic_map_t FINDMUG_COMMAND:command_t; do
  channel=${pair%%:*}
  type=${pair#*:}
  # Columns: Channel, Type, Num Msgs, ..., Undecodable (last). The spy shows the type of a
  # channel only when a class on its class path has the message's fingerprint.
  if ! awk -F'\t' -v c="$channel" -v t="$type" \
        '$1 == c && $2 == t && $3 > 0 && $NF == 0 { found = 1 } END { exit !found }' \
        "$work/table.txt"; then
    echo "spy test: $channel not decoded as $type (or undecodable messages)"
    status=1
  fi
done
[[ $status -eq 0 ]] && echo "spy test: every findmug channel decoded"
exit $status
