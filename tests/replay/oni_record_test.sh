#!/usr/bin/env bash
# oni_record_test.sh — findmug-oni-record end to end, no camera, no network:
# NYU frames -> .oni (OpenNI 1.5 recorder) -> OpenNI2 playback in findmug-grab
# -> an LCM log file, which must hold every frame at full size.
#
#   oni_record_test.sh --oni-record B --grab B --probe B
#
# Exit 0 pass, 1 fail, 77 data missing outside CI.
set -euo pipefail
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ONI_RECORD="" GRAB="" PROBE=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --oni-record) ONI_RECORD=$2; shift 2 ;;
    --grab) GRAB=$2; shift 2 ;;
    --probe) PROBE=$2; shift 2 ;;
    *) echo "oni_record_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
DATA_ROOT="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}"
NYU="$DATA_ROOT/nyuv2_labeled"
if [[ ! -d "$NYU/rgb" ]]; then
  [[ "${CI:-}" == true ]] && { echo "oni_record_test: FAILED: $NYU missing" >&2; exit 1; }
  echo "oni_record_test: SKIPPED: $NYU missing"; exit 77
fi
WORK="$(mktemp -d /tmp/findmug-oni.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT

"$ONI_RECORD" --source "dataset:$NYU" --count 4 --rate 5 --out "$WORK/nyu.oni"
# OpenNI2 plays it as fast as possible into a log file (file:// LCM: no network).
"$GRAB" --source "openni2:$WORK/nyu.oni?realtime=0" --url "file://$WORK/oni.lcm?mode=w"
"$PROBE" --inspect-log "$WORK/oni.lcm" | tee "$WORK/inspect.txt"
grep -qx "frames 4" "$WORK/inspect.txt" || { echo "oni_record_test: FAILED: expected 4 frames" >&2; exit 1; }
grep -qx "size 640x480" "$WORK/inspect.txt" || { echo "oni_record_test: FAILED: expected 640x480" >&2; exit 1; }

# A source that yields nothing must be an error, not an empty file.
mkdir -p "$WORK/empty/rgb" "$WORK/empty/depth"
if "$ONI_RECORD" --source "dataset:$WORK/empty" --out "$WORK/empty.oni" 2> "$WORK/err.txt"; then
  echo "oni_record_test: FAILED: an empty source was accepted" >&2; exit 1
fi
cat "$WORK/err.txt"
echo "oni_record_test: PASSED"
