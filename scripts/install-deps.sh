#!/usr/bin/env bash
# Installs everything indentsim needs on a fresh Debian 12 machine, idempotently.
# Toolchain, CMake and every library come from Debian's packages; nothing else is downloaded.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libsundials-dev libsuitesparse-dev libeigen3-dev libfmt-dev
  libgtest-dev libtomlplusplus-dev libcli11-dev
  libcsv-dev                 # CSV reader of measured tip profiles and load-depth curves
  nlohmann-json3-dev         # JSON: summary.json read back and analysis.json (indentsim analyze)
  libceres-dev               # Ceres Solver: the bounded Levenberg-Marquardt of indentsim fit
  libopenblas0-pthread       # BLAS for CHOLMOD's supernodal factorization (takes over libblas.so.3)
  python3 python3-matplotlib
  python3-dev pybind11-dev python3-numpy  # the Python module (build/python/indentsim)
  python3-dask python3-distributed python3-tqdm  # sweeps on Dask distributed, with a progress bar
  clang libclang-rt-14-dev   # libFuzzer targets (scripts/fuzz.sh)
  calculix-ccx               # CalculiX, the independent solver of tests CalculiX.* (benchmarks/calculix)
  libomp-14-dev              # OpenMP for clang: Debian's SUNDIALS CMake package requires OpenMP of the configuring compiler
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
