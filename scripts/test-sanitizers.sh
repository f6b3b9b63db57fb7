#!/usr/bin/env bash
# The sanitizer half of CI (run by .ci/run after scripts/test.sh):
#   build-asan clang-14, ASan + UBSan (+ libFuzzer coverage, FINDMUG_FUZZ=ON):
#               the unit tests, the io integration tests (LCM codecs, wire fields,
#               frame sources) and the daemon's building blocks; then every fuzz
#               target for FUZZ_SECONDS (default 20) from the committed corpus;
#   build-tsan clang-14, TSan: the daemon's queue/stage tests, the threaded
#               pipeline end to end and the object search sink's worker.
# Only the targets these runs need are built (the sanitizer builds are 2-3x
# slower to compile and run than Release). Every sanitizer report is fatal.
#
#   scripts/test-sanitizers.sh [asan|tsan|fuzz]...   (default: all three)
#   ASAN_BUILD_DIR=build-fuzz scripts/test-sanitizers.sh asan   (reuse scripts/fuzz.sh's build)
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${JOBS:-$(nproc)}
ASAN_DIR=${ASAN_BUILD_DIR:-build-asan}
TSAN_DIR=${TSAN_BUILD_DIR:-build-tsan}
STEPS=("$@")
source scripts/build-env.sh
[[ ${#STEPS[@]} -gt 0 ]] || STEPS=(asan fuzz tsan)
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)

configure() {  # DIR EXTRA-ARGS...
  local dir=$1; shift
  [[ -f "$dir/CMakeCache.txt" ]] && return 0
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DFINDMUG_BUILD_BENCHMARKS=OFF "${launcher[@]}" "$@"
}
unit_targets() {
  for f in tests/unit/*/*_test.cpp; do printf -- '--target %s ' "$(basename "$f" .cpp)"; done
}
timed() {  # LABEL COMMAND...
  local label=$1 start=$SECONDS; shift
  "$@"
  echo "test-sanitizers: $label took $((SECONDS - start)) s"
}

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp}

ASAN_SKIPPED_SWEEPS='^(TableMapSynth\.DriveThroughApartmentsMapsEachTableOnce|GroundOnNyu\.(GravitySourceGivesEveryFrameAGround|EstimateAgreesWithFloorLabelFit|GravityWithoutLabelsFindsTheLabelledFloorHeight)|SynthRender\.TableTopPixelsLieInsideTheTruePolygon)$'

for step in "${STEPS[@]}"; do
  case "$step" in
    asan)
      configure "$ASAN_DIR" -DFINDMUG_FUZZ=ON
      # shellcheck disable=SC2046
      timed "asan build" cmake --build "$ASAN_DIR" -j"$JOBS" $(unit_targets) --target lcm_codec_test \
        --target lcm_fields_test --target sources_test --target bus_test --target udpm_test --target daemon_queue_test --target findmug-grab \
        --target replay_check_test
      # Not under ASan: five sweeps that run code covered here by smaller tests over many
      # frames again (52, 49, 35, 30 and 24 s under ASan, 2026-11-26; perf-log §10,
      # "Sanitizer runs"). They run in the Release suite of scripts/test.sh.
      timed "asan tests" ctest --test-dir "$ASAN_DIR" --output-on-failure -j"$JOBS" --timeout 1800 \
        -L '^(unit|io)$' -E "$ASAN_SKIPPED_SWEEPS"
      timed "asan daemon blocks" ctest --test-dir "$ASAN_DIR" --output-on-failure -j"$JOBS" \
        -R '^(BoundedQueue|ReorderBuffer|Stage|LatencyWindow|RateMeter|WatchdogGate|DaemonConfig)\.' ;;
    fuzz)
      # fuzz.sh sets its own ASAN_OPTIONS (a small quarantine, memory handed back to
      # the OS): with the test options above, ASan's quarantine alone trips the
      # 256 MB RSS limit after ~30k inputs and reads as an out-of-memory finding.
      configure "$ASAN_DIR" -DFINDMUG_FUZZ=ON
      timed "fuzz ${FUZZ_SECONDS:-20} s per target" \
        env -u ASAN_OPTIONS BUILD_DIR="$ASAN_DIR" JOBS="$JOBS" BUILD_JOBS="$JOBS" \
          scripts/fuzz.sh "${FUZZ_SECONDS:-20}" ;;
    tsan)
      configure "$TSAN_DIR" -DFINDMUG_SANITIZE=thread
      timed "tsan build" cmake --build "$TSAN_DIR" -j"$JOBS" --target daemon_queue_test \
        --target daemon_pipeline_test --target daemon_fault_test --target daemon_find_test \
        --target findmugd
      timed "tsan tests" ctest --test-dir "$TSAN_DIR" --output-on-failure -j"$JOBS" --timeout 1800 \
        -R '^(BoundedQueue|ReorderBuffer|Stage|LatencyWindow|RateMeter|WatchdogGate|DaemonPipeline|DaemonFaults|DaemonFind)\.' ;;
    *) echo "test-sanitizers: unknown step '$step' (asan, fuzz, tsan)" >&2; exit 2 ;;
  esac
done
