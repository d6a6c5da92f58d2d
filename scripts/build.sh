#!/usr/bin/env bash
# Configures and builds indentsim (Release) in ./build.  Assumes the dependencies are installed.
#   ./scripts/build.sh             everything: the CLI, the Python module, tests, benchmarks
#   ./scripts/build.sh TARGET...   only those targets (the demo builds indentsim_cli alone)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build build -j "$jobs" "${targets[@]}"
