#!/usr/bin/env bash
# Installs the Debian 12 packages findmug needs to build, test and run.
# Idempotent: packages already present are skipped, so a second run is quick.
# Used by both README commands and by .ci/run.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  # the linker (CMakeLists.txt: FINDMUG_LLD), ~3x faster than GNU ld on the test programs
  lld
  # messaging: liblcm-dev forgets libglib2.0-dev, without which `pkg-config lcm` fails
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
  # perception
  libpcl-dev libeigen3-dev libopenni2-dev libopenni-dev
  # logging, config, service integration
  libspdlog-dev libfmt-dev libyaml-cpp-dev libsystemd-dev systemd
  # image and data formats
  libpng-dev libjpeg-dev zlib1g-dev libdeflate-dev libhdf5-dev libtiff-dev
  # the gradient-boosted learner (learner.kind = xgboost)
  libxgboost-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # command-line flags of the programs
  libcli11-dev
  # lcm-spy (Java) under a virtual display, for the screenshot script
  default-jdk-headless libjchart2d-java xvfb x11-apps imagemagick
  # network namespaces for the udpm tests
  iproute2 util-linux
  # sanitizer builds and fuzzing (scripts/test-sanitizers.sh, scripts/fuzz.sh)
  clang-14 libfuzzer-14-dev ccache
  # Debian packages (scripts/package.sh) and their checks (label package)
  dpkg-dev lintian adduser
  # findmug-web: HTTP server and JSON; its browser test drives Debian's chromium with
  # puppeteer-core from npm (clients/web/test: npm ci, never a downloaded browser)
  libcpp-httplib-dev nlohmann-json3-dev chromium
)
# Node.js and npm for that test: Debian's, unless the machine has them already (a
# NodeSource nodejs ships npm itself and conflicts with Debian's npm package).
command -v node >/dev/null || packages+=(nodejs)
command -v npm >/dev/null || packages+=(npm)

# findmug-web's browser test drives /usr/bin/chromium with puppeteer-core (npm), exactly as
# clients/web/test/package-lock.json pins it; puppeteer-core never downloads a browser.
install_web_test_modules() {
  local dir
  dir="$(cd "$(dirname "$0")/.." && pwd)/clients/web/test"
  [[ -f "$dir/package-lock.json" ]] || return 0
  if [[ ! -d "$dir/node_modules/puppeteer-core" ||
        "$dir/package-lock.json" -nt "$dir/node_modules/.package-lock.json" ]]; then
    echo "install-deps: npm ci in clients/web/test (puppeteer-core)"
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  install_web_test_modules
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get -o DPkg::Lock::Timeout=600 update -q
$SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -q --no-install-recommends "${missing[@]}"
install_web_test_modules
