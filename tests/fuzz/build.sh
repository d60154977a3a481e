#!/bin/bash
# Configures and builds the libFuzzer targets (tests/fuzz/targets) with clang in BUILD_DIR.
#   build.sh BUILD_DIR [CXX]      CXX defaults to clang++; HIL_FUZZ_JOBS (default 1) jobs
# Only the parser sources the targets need are compiled (a few minutes on 2 cores the first time).
set -euo pipefail
here=$(dirname "$(readlink -f "$0")")
bin=${1:?usage: build.sh BUILD_DIR [CXX]}
cxx=${2:-clang++}
mkdir -p "$bin"
if [[ ! -f $bin/build.ninja ]]; then
  cmake -S "$here/targets" -B "$bin" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" > "$bin/configure.log" 2>&1 \
    || { cat "$bin/configure.log" >&2; exit 1; }
fi
cmake --build "$bin" -j "${HIL_FUZZ_JOBS:-1}"
