# Sourced by the scripts that configure a build tree (configure.sh, which test.sh, demo.sh,
# bench.sh and fuzz-seeds.sh share; test-sanitizers.sh, fuzz.sh, package.sh).
#
# New build trees use Ninja when it is installed (scripts/install-deps.sh installs it).
# With make, the targets named on one `cmake --build --target a --target b ...` are built
# one after another (CMake's top-level Makefile is .NOTPARALLEL): a sanitizer build of ~35
# one-file test programs then ran on one core, 850 s where Ninja takes 480 s (BENCHMARKS.md
# 10). An existing tree keeps the generator it was made with; CMAKE_GENERATOR in the
# environment still overrides.
if [[ -z "${CMAKE_GENERATOR:-}" ]] && command -v ninja >/dev/null; then
  export CMAKE_GENERATOR=Ninja
fi

# ccache: paths below the checkout are hashed relative to it (and the build directory is not
# hashed), so a fresh clone elsewhere, as CI makes, reuses what an earlier build compiled.
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(pwd -P)}
export CCACHE_NOHASHDIR=${CCACHE_NOHASHDIR:-1}
