#!/usr/bin/env bash
# One command on a fresh Debian 12 machine: install the dependencies, build, and run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
./scripts/install-deps.sh
echo "test.sh: install took $((SECONDS - start)) s"
start=$SECONDS
./scripts/build.sh
echo "test.sh: build took $((SECONDS - start)) s"
jobs=$(nproc 2>/dev/null || echo 2)
ctest --test-dir build --output-on-failure -j "$jobs"
