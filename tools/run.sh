#!/usr/bin/env bash
# The main job: set up and build, then load MuJoCo's humanoid.xml and the 15-link chain into both
# engines, run forward dynamics at random states and print the largest differences.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
./build/tools/novaphy_validate "$@"
