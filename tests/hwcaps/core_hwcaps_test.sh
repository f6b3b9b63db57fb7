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
if [[ ! -d "$DATA/nyuv2_labeled" ]]; then
  if [[ "${CI:-}" == "true" ]]; then
    echo "FAIL: $DATA/nyuv2_labeled is missing (set FINDMUG_DATA)" >&2
    exit 1
  fi
  echo "SKIP: $DATA/nyuv2_labeled is missing (set FINDMUG_DATA)"
  exit 77
fi
export FINDMUG_DATA="$DATA"

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BUILD/tools/findmug-synth" --seed 7 --frames 12 --out "$WORK/synth" > /dev/null

plain() { GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2 "$@"; }
FRAME_ARGS=(--model "$MODEL" --passes 1 --set features.regions=true --set features.scene=true)
status=0
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
  if [[ "$v3_lib" != *"/glibc-hwcaps/x86-64-v3/"* ]]; then
    echo "FAIL: the loader did not pick the x86-64-v3 copy ($v3_lib)" >&2
    status=1
  fi
  if [[ -z "$plain_lib" || "$plain_lib" == *"/glibc-hwcaps/"* ]]; then
    echo "FAIL: GLIBC_TUNABLES did not give the plain build ($plain_lib)" >&2
    status=1
  fi
  frames=$(wc -l < "$WORK/v3-$data.txt")
  if [[ $frames -lt 12 ]]; then
    echo "FAIL: $data: the digest has $frames frames" >&2
    status=1
  fi
  if ! cmp -s "$WORK/v3-$data.txt" "$WORK/plain-$data.txt"; then
    echo "FAIL: $data: the two builds' frame digests differ:" >&2
    diff "$WORK/plain-$data.txt" "$WORK/v3-$data.txt" | head -20 >&2
    status=1
  else
    echo "$data: $frames frames, the same digest from both builds"
  fi
done

FINDMUG_TABLES_DUMP="$WORK/v3-tables.txt" "$BUILD/tests/bench/tables_bench" \
  --benchmark_filter=NONE > /dev/null
FINDMUG_TABLES_DUMP="$WORK/plain-tables.txt" plain "$BUILD/tests/bench/tables_bench" \
  --benchmark_filter=NONE > /dev/null
tables=$(grep -c '^  table ' "$WORK/v3-tables.txt" || true)
if [[ $tables -lt 10 ]]; then
  echo "FAIL: the tables dump holds $tables tables" >&2
  status=1
elif ! cmp -s "$WORK/v3-tables.txt" "$WORK/plain-tables.txt"; then
  echo "FAIL: the two builds' table dumps differ:" >&2
  diff "$WORK/plain-tables.txt" "$WORK/v3-tables.txt" | head -20 >&2
  status=1
else
  echo "tables: $tables tables, the same dump from both builds"
fi
exit $status
