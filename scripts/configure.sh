#!/usr/bin/env bash
# The one configure step of the build tree the README's commands share:
#
#   scripts/configure.sh BUILD_DIR [more cmake arguments]
#
# scripts/demo.sh, scripts/test.sh, scripts/bench.sh and scripts/fuzz-seeds.sh all configure
# build/ (or $BUILD_DIR) through it, with the same flags, so whichever runs second finds the
# tree configured as it needs and compiles only the targets the first did not build:
#   Release; warnings as errors (as CI builds); prefix /usr, the tree the package test turns
#   into the Debian package (compiled-in default paths follow it; the demo passes --config and
#   --model itself); ccache as the compiler launcher when installed (scripts/install-deps.sh
#   installs it), so a rebuild of unchanged sources is cheap.
# Other trees are configured differently on purpose: build-package/ (scripts/package.sh, no
# tests), build-asan/, build-tsan/ (scripts/test-sanitizers.sh) and the fuzzing tree
# (scripts/fuzz.sh), all with other compilers or options.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ $# -lt 1 ]]; then
  echo "usage: scripts/configure.sh BUILD_DIR [cmake arguments]" >&2
  exit 2
fi
BUILD_DIR=$1
shift
source scripts/build-env.sh
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
exec cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DFINDMUG_WERROR=ON \
  -DCMAKE_INSTALL_PREFIX=/usr "${launcher[@]}" "$@"
