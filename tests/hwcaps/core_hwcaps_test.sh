#!/usr/bin/env bash
# core_hwcaps_test.sh — the x86-64-v3 copy of the core library
# (BUILD/src/glibc-hwcaps/x86-64-v3, src/CMakeLists.txt) gives the same results
# to the bit as the plain x86-64 build, and the loader really picks it.
#
#   core_hwcaps_test.sh BUILD_DIR MODEL
#
# Each program runs twice: as the loader chooses (the copy, on a CPU with AVX2),
# and with GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2, under which the loader takes
# the CPU for one without AVX2 and loads the plain build (the plain build's own
# AVX2 paths still run: they ask the CPU, not glibc). Compared:
#  - frame_cpu --digest (ground plane, label image, table hull sizes per frame)
#    on the 31 NYU frames and on 12 rendered apartment frames (table-rich);
#  - tables_bench's dump (every field of every table, floats in hex, NYU frames
#    with ground-truth labels and rendered ones, strides 1 and 2).
# Exit 77 (ctest: skipped) where the copy cannot be loaded at all (a CPU or C
# library without x86-64-v3 support), or where the NYU data is missing outside CI.
set -euo pipefail
BUILD=$(cd "$1" && pwd)
MODEL=$2
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
DATA=${FINDMUG_DATA:-$ROOT/../shared/data}
COPY="$BUILD/src/glibc-hwcaps/x86-64-v3"

if [[ ! -e "$COPY/libfindmug_core.so.0.1" ]]; then
  echo "FAIL: no x86-64-v3 copy of the core in $COPY" >&2
  exit 1
fi
LOADER=/lib64/ld-linux-x86-64.so.2
if ! "$LOADER" --help 2>/dev/null | grep -q 'x86-64-v3 (supported'; then
  echo "SKIP: this CPU or C library does not support x86-64-v3 ($LOADER --help):" \
       "the copy is never loaded here"
  exit 77
fi
SKIP_NAME=core_hwcaps_test
source "$ROOT/tests/support/skip.sh"
[[ -d "$DATA/nyuv2_labeled" ]] || skip "$DATA/nyuv2_labeled is missing (set FINDMUG_DATA)"
export FINDMUG_DATA="$DATA"

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BUILD/tools/findmug-synth" --seed 7 --frames 12 --out "$WORK/synth" > /dev/null

plain() { GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2 "$@"; }
status=0
fail() { echo "FAIL: $*" >&2; status=1; }
# expect_same NAME COUNT MINIMUM WHAT: $WORK/v3-NAME and $WORK/plain-NAME hold the same bytes,
# and COUNT (of WHAT in them) is at least MINIMUM (the runs did produce something).
expect_same() {
  local name=$1 count=$2 minimum=$3 what=$4
  if [[ $count -lt $minimum ]]; then
    fail "$name: $count $what, expected at least $minimum"
  elif ! cmp -s "$WORK/v3-$name" "$WORK/plain-$name"; then
    fail "$name: the two builds' outputs differ:"
    diff "$WORK/plain-$name" "$WORK/v3-$name" | head -20 >&2
  else
    echo "$name: $count $what, the same from both builds"
  fi
}
# The shipped model's settings (models/README.md).
FRAME_ARGS=(--model "$MODEL" --passes 1 --set features.regions=true --set features.scene=true
            --set learner.classes=nyu13 --set features.objects=true --set features.objects_columns=relations)
for data in nyu synth; do
  data_args=()
  [[ $data == synth ]] && data_args=(--data "$WORK/synth")
  "$BUILD/tests/bench/frame_cpu" "${FRAME_ARGS[@]}" "${data_args[@]}" \
    --digest "$WORK/v3-$data.txt" > "$WORK/v3-$data.out"
  plain "$BUILD/tests/bench/frame_cpu" "${FRAME_ARGS[@]}" "${data_args[@]}" \
    --digest "$WORK/plain-$data.txt" > "$WORK/plain-$data.out"
  v3_lib=$(sed -n 's/^core library: //p' "$WORK/v3-$data.out")
  plain_lib=$(sed -n 's/^core library: //p' "$WORK/plain-$data.out")
  echo "$data: as the loader chooses: $v3_lib; with the tunable: $plain_lib"
  [[ "$v3_lib" == *"/glibc-hwcaps/x86-64-v3/"* ]] ||
    fail "the loader did not pick the x86-64-v3 copy ($v3_lib)"
  [[ -n "$plain_lib" && "$plain_lib" != *"/glibc-hwcaps/"* ]] ||
    fail "GLIBC_TUNABLES did not give the plain build ($plain_lib)"
  expect_same "$data.txt" "$(wc -l < "$WORK/v3-$data.txt")" 12 "frame digests"
done

FINDMUG_TABLES_DUMP="$WORK/v3-tables.txt" "$BUILD/tests/bench/tables_bench" \
  --benchmark_filter=NONE > /dev/null
FINDMUG_TABLES_DUMP="$WORK/plain-tables.txt" plain "$BUILD/tests/bench/tables_bench" \
  --benchmark_filter=NONE > /dev/null
expect_same tables.txt "$(grep -c '^  table ' "$WORK/v3-tables.txt" || true)" 10 "tables"
exit $status
