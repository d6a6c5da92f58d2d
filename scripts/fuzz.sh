#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (plus ASan and UBSan) in ./build-fuzz and runs each for
# a bounded time (default 60 s; first argument overrides), starting from the seed corpus in
# fuzz/corpus.  New inputs go to a scratch folder, not into the repository.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DINDENTSIM_BUILD_PYTHON=OFF \
      -DINDENTSIM_SANITIZE=address,undefined -DINDENTSIM_BUILD_FUZZERS=ON \
      -DINDENTSIM_BUILD_TESTS=OFF -DINDENTSIM_BUILD_BENCHMARKS=OFF
cmake --build build-fuzz -j "$jobs" --target fuzz_load_case fuzz_checkpoint
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for target in load_case checkpoint; do
  mkdir -p "$scratch/$target"
  echo "fuzzing $target for ${seconds}s"
  ASAN_OPTIONS=detect_leaks=1 ./build-fuzz/fuzz/fuzz_$target -max_total_time="$seconds" -rss_limit_mb=4096 \
    -timeout=30 -print_final_stats=1 "$scratch/$target" "fuzz/corpus/$target" 2>&1 | tail -n 12
done
