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
# Prefix /usr: the tree the package test (label package) turns into the Debian package.
# ccache (installed by install-deps.sh) makes a rebuild of unchanged sources cheap.
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DFINDMUG_WERROR=ON -DCMAKE_INSTALL_PREFIX=/usr \
  "${launcher[@]}"
cmake --build "$BUILD_DIR" -j"$JOBS"
# Tests that need the third-party data read it from $FINDMUG_DATA or
# ../shared/data; under CI=true a missing data set is a failure, not a skip.
ctest --test-dir "$BUILD_DIR" --output-on-failure -j"$JOBS" --timeout 900
