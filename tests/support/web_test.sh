# tests/support/web_test.sh — what findmug-web's browser tests share. Source it after
# skip.sh (which defines skip and need_tools, and takes SKIP_NAME):
#
#   web_test_needs_browser          node, chromium (FINDMUG_CHROMIUM) and puppeteer-core in
#                                   clients/web/test, or skip (77; a failure under CI=true)
#   web_test_enter_netns ARGS...    re-runs the calling script with ARGS in a private network
#                                   namespace (nothing can leave the machine) and, inside it,
#                                   brings lo up with a multicast route for LCM's udpm
#   web_test_workdir PREFIX         makes $WORK (and $OUT when empty), kills the processes in
#                                   the array `pids` and removes $WORK at exit, and defines
#                                   fail MESSAGE (prints the tails of $WORK/*.log, exits 1)
#   web_test_wait_for_port PORT PID until 127.0.0.1:PORT accepts a connection (10 s); fails
#                                   when process PID exits first

web_test_needs_browser() {
  need_tools node unshare ip
  [[ -x "${FINDMUG_CHROMIUM:-/usr/bin/chromium}" ]] ||
    skip "${FINDMUG_CHROMIUM:-/usr/bin/chromium} not installed (scripts/install-deps.sh)"
  [[ -d "$SOURCE_DIR/clients/web/test/node_modules/puppeteer-core" ]] ||
    skip "puppeteer-core not installed (scripts/install-deps.sh runs npm ci in clients/web/test)"
}

web_test_enter_netns() {
  if [[ "${FINDMUG_WEB_NETNS:-}" != 1 ]]; then
    local ns=(unshare --net)
    [[ $EUID -eq 0 ]] || ns=(unshare --net --map-root-user)
    exec "${ns[@]}" env FINDMUG_WEB_NETNS=1 bash "$0" "$@"
  fi
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
}

web_test_workdir() {
  WORK=$(mktemp -d "/tmp/$1.XXXXXX")
  [[ -n "${OUT:-}" ]] || OUT=$WORK
  mkdir -p "$OUT"
  pids=()
  trap web_test_cleanup EXIT
}

web_test_wait_for_port() {  # PORT PID: until 127.0.0.1:PORT accepts (10 s), failing if PID exits
  local _
  for _ in $(seq 100); do
    (exec 3<>/dev/tcp/127.0.0.1/"$1") 2>/dev/null && return 0
    kill -0 "$2" 2>/dev/null || fail "the server (pid $2) exited"
    sleep 0.1
  done
}

web_test_cleanup() {
  local pid
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  rm -rf "$WORK"
}

fail() {
  echo "$SKIP_NAME: FAILED: $*" >&2
  local log
  for log in "$WORK"/*.log; do
    [[ -f "$log" ]] || continue
    echo "--- $log"
    tail -25 "$log"
  done >&2
  exit 1
}
