#!/usr/bin/env bash
# frame_cpu_per_frame_test.sh — frame_cpu --per-frame writes one row per timed
# frame, and each row's stages add up to its total (perf-log §9w reads the
# slow frames of a stream from it).
#
#   frame_cpu_per_frame_test.sh BUILD_DIR MODEL
#
# Runs the 31 NYU frames once after the warm-up pass. Checks the header, that
# the rows are exactly the runs the summary counts ("medians over the N of M
# runs"), one per frame in the data set's order, with non-negative times whose
# stage columns sum to the total (the context round is off). Exit 77 (ctest:
# skipped) when the NYU data is missing outside CI; under CI=true that fails.
set -euo pipefail
BUILD=$(cd "$1" && pwd)
MODEL=$2
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
DATA=${FINDMUG_DATA:-$ROOT/../shared/data}
SKIP_NAME=frame_cpu_per_frame_test
source "$ROOT/tests/support/skip.sh"
[[ -d "$DATA/nyuv2_labeled" ]] || skip "$DATA/nyuv2_labeled is missing (set FINDMUG_DATA)"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

"$BUILD/tests/bench/frame_cpu" --model "$MODEL" --data "$DATA/nyuv2_labeled" --passes 1 \
  --set features.regions=true --set features.scene=true --set learner.classes=nyu13 \
  --set features.objects=true --set features.objects_columns=relations \
  --per-frame "$TMP/frames.csv" \
  > "$TMP/summary.txt"
runs=$(sed -n 's/.*medians over the \([0-9]*\) of \([0-9]*\) runs.*/\1/p' "$TMP/summary.txt")
if [[ -z "$runs" || "$runs" -lt 1 ]]; then
  echo "FAIL: no run count in frame_cpu's summary:" >&2
  cat "$TMP/summary.txt" >&2
  exit 1
fi
header="pass,frame,cloud,normals,ground,oversegmentation,features,regions,forest,mrf,labels,tables,objects,total"
if [[ "$(head -n 1 "$TMP/frames.csv")" != "$header" ]]; then
  echo "FAIL: header is '$(head -n 1 "$TMP/frames.csv")', expected '$header'" >&2
  exit 1
fi
rows=$(($(wc -l < "$TMP/frames.csv") - 1))
if [[ "$rows" != "$runs" ]]; then
  echo "FAIL: $rows rows in --per-frame, the summary counts $runs runs" >&2
  exit 1
fi
# Frames in the data set's order (names ascend), each once, every time >= 0,
# the stages summing to the total within the rounding of 3 decimals.
awk -F, 'NR > 1 {
  if (NF != 14) { printf "FAIL: row %d has %d fields\n", NR, NF; bad = 1; exit }
  if ($1 != 0) { printf "FAIL: row %d: pass %s, expected 0\n", NR, $1; bad = 1; exit }
  if ($2 == "" || (NR > 2 && $2 <= last)) {
    printf "FAIL: row %d: frame %s after %s\n", NR, $2, last; bad = 1; exit
  }
  last = $2
  sum = 0
  for (i = 3; i <= 13; ++i) {
    if ($i < 0) { printf "FAIL: row %d: column %d is %s\n", NR, i, $i; bad = 1; exit }
    sum += $i
  }
  if ($14 <= 0 || sum - $14 > 0.01 || $14 - sum > 0.01) {
    printf "FAIL: row %d (%s): stages sum to %.3f, total %s\n", NR, $2, sum, $14; bad = 1; exit
  }
} END { exit bad }' "$TMP/frames.csv"
echo "PASS: $rows frames, one row each, stages sum to the totals"
