#!/usr/bin/env bash
# Builds the Debian packages from this checkout:
#   build-package/packages/findmug_<version>_<arch>.deb      (programs, unit, config, models)
#   build-package/packages/findmug-dev_<version>_<arch>.deb  (headers, .lcm, CMake package)
# Installs missing build dependencies (scripts/install-deps.sh), configures a separate build
# tree for the system prefix /usr without tests and benchmarks, builds, runs cpack and
# lintian. BUILD_DIR overrides the build tree; JOBS the parallel compile jobs.
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR=${BUILD_DIR:-build-package}
JOBS=${JOBS:-$(nproc)}

scripts/install-deps.sh
source scripts/build-env.sh
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
  -DFINDMUG_BUILD_TESTS=OFF -DFINDMUG_BUILD_BENCHMARKS=OFF
cmake --build "$BUILD_DIR" -j"$JOBS"
(cd "$BUILD_DIR" && cpack -G DEB)
if command -v lintian >/dev/null; then
  lintian --allow-root "$BUILD_DIR"/packages/*.deb || true
fi
echo "package.sh: packages in $BUILD_DIR/packages:"
ls -1 "$BUILD_DIR"/packages/*.deb
