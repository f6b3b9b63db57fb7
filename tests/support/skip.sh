# skip.sh — sourced by the shell tests that need root or outside tools:
#   SKIP_NAME="spy test"; source "$source_dir/tests/support/skip.sh"
#   need_root "unshare --net"; need_tools unshare ip Xvfb
# A missing requirement skips the test (exit 77, ctest SKIP_RETURN_CODE) — except under
# CI=true, where everything must be there and a missing piece fails the test (exit 1).

skip() {
  if [[ "${CI:-}" == "true" ]]; then
    echo "${SKIP_NAME:?}: FAIL under CI=true: $*" >&2
    exit 1
  fi
  echo "${SKIP_NAME:?}: SKIPPED: $*"
  exit 77
}

# need_root WHY: skip unless running as root.
need_root() {
  [[ $(id -u) -eq 0 ]] || skip "needs root ($1)"
}

# need_tools TOOL...: skip unless every TOOL is on PATH.
need_tools() {
  local tool
  for tool in "$@"; do
    command -v "$tool" >/dev/null || skip "$tool not installed"
  done
}
