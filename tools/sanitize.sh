#!/usr/bin/env bash
# Sanitizer runs (docs/sanitizers.md), on a machine set up by tools/setup.sh (run as root):
#   bash tools/sanitize.sh asan   ASan + UBSan build in build-asan/ and the whole suite under it
#   bash tools/sanitize.sh tsan   TSan build in build-tsan/ of the threaded tests (ctest label
#                                 `threads`: drivers, acquisition, the DDS bus, the diagnosis'
#                                 folds) and those tests
# Both use CMakePresets.json (cmake --preset / ctest --preset asan|tsan); any sanitizer report
# fails its test. Extra arguments go to ctest (e.g. -R EndToEnd).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${HIL_JOBS:-$(nproc)}"
kind="${1:-}"
shift || true

# The targets behind label `threads` (tests/{drivers,acquisition,idl,benchmarks,diagnosis}/CMakeLists.txt).
tsan_targets=(test_drivers test_rig_service test_acquisition test_acquisition_e2e test_idl bench_rig test_diagnose_engine)

case "$kind" in
  asan | tsan) ;;
  *) echo "usage: bash tools/sanitize.sh asan|tsan [ctest arguments]" >&2; exit 2 ;;
esac
bash "$here/tools/setup.sh" deps
cd "$here"
start=$(date +%s)
cmake --preset "$kind" >/dev/null
if [[ $kind == asan ]]; then
  bash "$here/tools/setup.sh" vm  # the vcan tests are part of the whole suite
  cmake --build --preset asan -j "$jobs"
else
  cmake --build --preset tsan -j "$jobs" --target "${tsan_targets[@]}"
fi
echo "sanitize: $kind build took $(($(date +%s) - start)) s"
# Label `blind` (the blind diagnoses: hidden effects, the independent truth's runs; pure numerics,
# minutes each under ASan, their code covered by the engine and CLI tests) is left out to keep
# CI's budget.
exclude=()
[[ $kind == asan ]] && exclude=(-LE blind)
ctest --preset "$kind" -j "$jobs" "${exclude[@]}" "$@"
