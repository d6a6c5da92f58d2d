#!/usr/bin/env bash
# One command on a fresh Debian 12 machine: install the dependencies, build the indentsim command
# (only it: the tests, benchmarks and Python module are the test command's), and run the default
# load case.  Prints where the P-alpha curve went.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh indentsim_cli
./build/indentsim run loadcases/elastic.toml
echo "The P-alpha curve of loadcases/elastic.toml is in out/elastic/curve.csv"
