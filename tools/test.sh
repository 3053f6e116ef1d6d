#!/usr/bin/env bash
# Every test: set up and build, then ctest (GoogleTest and the pytest suite of the binding).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cd build
ctest --output-on-failure -j"$(nproc)"
