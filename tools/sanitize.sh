#!/usr/bin/env bash
# Sanitizer runs (docs/sanitizers.md), on a machine set up by tools/setup.sh (run as root):
#   bash tools/sanitize.sh asan     ASan + UBSan build in build-asan/ and the whole suite under it
#                                   (but the tests labelled `blind`, which that preset leaves out)
#   bash tools/sanitize.sh asan-io  the same build of the tests labelled `io` alone (drivers,
#                                   acquisition, the DDS bus, the file formats: the code that takes
#                                   outside input or runs device threads) and those tests: CI's stage
#   bash tools/sanitize.sh tsan     TSan build in build-tsan/ of the threaded tests (ctest label
#                                   `threads`: drivers, acquisition, the DDS bus, the diagnosis'
#                                   folds) and those tests
# All use CMakePresets.json (cmake --preset / ctest --preset asan|tsan); any sanitizer report
# fails its test. Extra arguments go to ctest (e.g. -R EndToEnd).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${HIL_JOBS:-$(nproc)}"
kind="${1:-}"
shift || true

# The targets behind label `threads` (tests/{drivers,acquisition,idl,benchmarks,diagnosis}/CMakeLists.txt).
tsan_targets=(test_drivers test_rig_service test_acquisition test_acquisition_e2e test_idl bench_rig test_diagnose_engine)

case "$kind" in
  asan | asan-io | tsan) ;;
  *) echo "usage: bash tools/sanitize.sh asan|asan-io|tsan [ctest arguments]" >&2; exit 2 ;;
esac
preset="${kind%-io}"
bash "$here/tools/setup.sh" deps
cd "$here"
start=$(date +%s)
cmake --preset "$preset" >/dev/null
filter=()
case "$kind" in
  asan)
    bash "$here/tools/setup.sh" vm  # the vcan tests are part of the whole suite
    cmake --build --preset asan -j "$jobs"
    ;;
  asan-io)
    cmake --build --preset asan -j "$jobs" --target hil_io_tests  # tests/CMakeLists.txt
    filter=(-L io)
    ;;
  tsan) cmake --build --preset tsan -j "$jobs" --target "${tsan_targets[@]}" ;;
esac
echo "sanitize: $kind build took $(($(date +%s) - start)) s"
# The asan preset neither builds nor registers the tests labelled `blind` (HIL_BLIND_TESTS=OFF: the
# blind diagnoses and calibrations, pure numerics, minutes each under ASan, their code covered by
# the engine, calibration and CLI tests).
ctest --preset "$preset" -j "$jobs" "${filter[@]}" "$@"
echo "sanitize: $kind took $(($(date +%s) - start)) s in all"
