#!/usr/bin/env bash
# Builds the library, CLI and tests with AddressSanitizer and UndefinedBehaviorSanitizer (gcc)
# in ./build-sanitize and runs the test suite once, but for the tests labelled slow (scene_slow
# included: ctest's -LE is a regular expression).  Those are long scenes and fits that repeat code
# the others already reach under the sanitizers (the fit's through the FitCli tests, finite
# strain's through the FiniteStrain suites): they were 60% of the suite's time and made the
# sanitizer pass the longest phase of CI.  The test command (scripts/test.sh) runs them all.
# Assumes the dependencies are installed.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DINDENTSIM_SANITIZE=address,undefined \
      -DINDENTSIM_BUILD_BENCHMARKS=OFF
cmake --build build-sanitize -j "$jobs"
# Leak checking stays on; SUNDIALS and KLU allocations are all owned by RAII handles.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-sanitize --output-on-failure -j "$jobs" -LE slow
