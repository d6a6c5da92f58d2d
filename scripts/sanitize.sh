#!/usr/bin/env bash
# Builds the library, CLI and tests with AddressSanitizer and UndefinedBehaviorSanitizer (gcc)
# in ./build-sanitize and runs the whole test suite once.  Assumes the dependencies are installed.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DINDENTSIM_SANITIZE=address,undefined \
      -DINDENTSIM_BUILD_BENCHMARKS=OFF
cmake --build build-sanitize -j "$jobs"
# Leak checking stays on; SUNDIALS and KLU allocations are all owned by RAII handles.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-sanitize --output-on-failure -j "$jobs"
