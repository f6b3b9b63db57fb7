#!/usr/bin/env bash
# The README's demo: installs what is missing, builds, and runs the daemon's
# main job on an embedded default — a synthetic apartment rendered by
# findmug-synth (no downloads, no external data) — then shows what findmugd
# published, as the navigation client and the label viewer receive it.
#
# LCM goes to a log file (file:// provider), so nothing leaves this machine.
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-demo-out}
FRAMES=${FRAMES:-20}
RATE_HZ=${RATE_HZ:-5}

rm -rf "$OUT"
mkdir -p "$OUT"
OUT_ABS=$(cd "$OUT" && pwd)

# Set-up output goes to a log; shown only when a step fails.
quietly() {
  if ! "$@" >>"$OUT_ABS/setup.log" 2>&1; then
    tail -n 40 "$OUT_ABS/setup.log"
    echo "demo: set-up step failed: $* (full log: $OUT/setup.log)" >&2
    exit 1
  fi
}
echo "== 0. Installing packages and building (log: $OUT/setup.log)"
quietly scripts/install-deps.sh
source scripts/build-env.sh
# The configure scripts/test.sh shares: its build reuses what this one compiled.
quietly scripts/configure.sh "$BUILD_DIR"
quietly cmake --build "$BUILD_DIR" -j"$(nproc)" --target findmugd findmug-synth \
  findmug-nav-client findmug-label-viewer
LOG="$OUT_ABS/findmug.lcmlog"

echo
echo "== 1. Rendering a synthetic apartment: $FRAMES frames, robot head camera, Kinect noise"
"$BUILD_DIR"/tools/findmug-synth --seed 7 --frames "$FRAMES" --fps "$RATE_HZ" --out "$OUT_ABS/apartment"

echo
echo "== 2. findmugd: replaying the frames at $RATE_HZ fps through the threaded pipeline"
echo "      (organized oversegmenter, committed model models/findmug-nyu-synth.fmf; LCM -> $LOG)"
# The synthetic-scene model learns the 8 labels without object features
# (models/README.md): the rendered frames have no NYU-13 classes to learn. The model
# records that, and findmugd takes it from the model. It is a format-3 file without
# the learned pairwise term, so its MRF is the paper's Potts.
"$BUILD_DIR"/daemon/findmugd --config daemon/findmugd.yaml \
  --model models/findmug-nyu-synth.fmf --set mrf.pairwise=potts \
  --source "dataset:$OUT_ABS/apartment?rate_hz=$RATE_HZ" \
  --lcm-url "file://$LOG?mode=w"

echo
echo "== 3. What a navigation client receives on FINDMUG_TABLES (search positions, visiting order)"
"$BUILD_DIR"/clients/findmug-nav-client --lcm-url "file://$LOG?mode=r&speed=0" | tail -n 25

echo
echo "== 4. Label images on FINDMUG_LABELS, pictures in $OUT/labels/"
echo "      (labels over the camera image with a legend, table hulls and numbered search"
echo "      positions; table_map.png / table_map.svg: the tables top-down around the robot)"
mkdir -p "$OUT_ABS/labels"
# The daemon does not republish the frames: --source gives the viewer the colour images
# and camera mount of the same replay, matched by sequence number.
"$BUILD_DIR"/clients/findmug-label-viewer --lcm-url "file://$LOG?mode=r&speed=0" \
  --source "dataset:$OUT_ABS/apartment" --out "$OUT_ABS/labels" | tail -n 8
ls "$OUT_ABS/labels" | sed -n '1p;$p' | sed 's/^/      /'

echo
echo "Done. Published LCM log: $LOG (inspect with findmug-spy, or replay with lcm-logplayer)."
