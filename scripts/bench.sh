#!/usr/bin/env bash
# scripts/bench.sh — the daemon benchmark in one command (not part of CI).
#
#   scripts/bench.sh                      # build/ , defaults: NYU + PCL + synthetic, 1/5/15/30 fps
#   scripts/bench.sh --duration 10 --datasets nyu    # a quicker look
#   BUILD_DIR=/tmp/b scripts/bench.sh
#
# Builds what the benchmark needs, then runs tests/bench/daemon_bench.sh with
# the given options. It writes BENCHMARKS-replay.md (machine, commit, command
# and tables; merged into BENCHMARKS.md by hand) and raw reports under
# $BUILD_DIR/bench-results/. Takes about 30 minutes with the defaults; needs
# root or unprivileged user namespaces (it runs in a private network namespace).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
source scripts/build-env.sh
scripts/configure.sh "$BUILD_DIR" > /dev/null    # the tree scripts/test.sh and demo.sh share
cmake --build "$BUILD_DIR" -j"$JOBS" --target findmugd findmug-replay findmug-replay-probe \
  findmug-sequential findmug-synth findmug-train
BUILD_DIR="$BUILD_DIR" exec tests/bench/daemon_bench.sh --build-dir "$BUILD_DIR" "$@"
