#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs the
# whole test suite (unit + integration + replay). Exits non-zero on failure.
#
#   scripts/test.sh            # build dir: build/
#   BUILD_DIR=/tmp/b scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}

scripts/install-deps.sh
source scripts/build-env.sh
# The configure scripts/demo.sh and scripts/bench.sh share (Release, warnings as errors,
# prefix /usr for the package test, ccache): after the demo only what it did not build compiles.
scripts/configure.sh "$BUILD_DIR"
cmake --build "$BUILD_DIR" -j"$JOBS"
# Tests that need the third-party data read it from $FINDMUG_DATA or
# ../shared/data; under CI=true a missing data set is a failure, not a skip.
ctest --test-dir "$BUILD_DIR" --output-on-failure -j"$JOBS" --timeout 900
