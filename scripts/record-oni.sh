#!/usr/bin/env bash
# scripts/record-oni.sh — record frames from any findmug frame source into an
# OpenNI .oni file, without a camera (see tools/oni_record/oni_writer.hpp).
#
#   scripts/record-oni.sh SOURCE OUT.oni [findmug-oni-record options]
#   scripts/record-oni.sh "dataset:../shared/data/nyuv2_labeled" nyu.oni --rate 5
#   scripts/record-oni.sh "lcm:FINDMUG_RGBD?url=file:///tmp/rec.lcm" rec.oni --timestamps source
#
# Options (passed on): --count N, --rate HZ (stamps frame i at i/HZ; default 30),
# --timestamps source, --depth-codec 16z|raw, --color-codec jpeg|raw.
# Play it back with findmugd --source openni2:OUT.oni, or findmug-grab.
set -euo pipefail
if [[ $# -lt 2 || "$1" == -h || "$1" == --help ]]; then
  sed -n '2,12p' "$0"
  exit $(( $# < 2 ? 2 : 0 ))
fi
source_spec=$1 out=$2
shift 2
root="$(cd "$(dirname "$0")/.." && pwd)"
exe="${BUILD_DIR:-$root/build}/tools/oni_record/findmug-oni-record"
if [[ ! -x "$exe" ]]; then
  exe="$(command -v findmug-oni-record || true)"
fi
[[ -n "$exe" && -x "$exe" ]] || {
  echo "record-oni: findmug-oni-record not built (cmake --build build --target findmug-oni-record)" >&2
  exit 1
}
exec "$exe" --source "$source_spec" --out "$out" "$@"
