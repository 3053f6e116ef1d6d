#!/usr/bin/env bash
# The main job: set up and build (tools/setup.sh), then batch-simulate a robot: an MJCF file (default
# bench/scenes/quadruped.xml) replicated into thousands of worlds (default 4096) and stepped for a few
# seconds by NovaPhy, then by MuJoCo 2.2.2 from the same file; prints both engines' robot-steps/s, the
# largest difference from MuJoCo's forward dynamics (novaphy_validate's check) and writes a picture of a
# few worlds to build/novaphy_showcase.png.
#   bash tools/run.sh [scene.xml] [--worlds N] [--seconds S] [--mujoco-worlds N] [--picture file.png] ...
# (every option: tools/showcase.cpp). A relative path names a file from the directory run.sh was called in.
set -euo pipefail
caller=$PWD
cd "$(dirname "$0")/.."
root=$PWD
bash tools/setup.sh
cd "$caller"
exec "$root/build/tools/novaphy_showcase" --picture "$root/build/novaphy_showcase.png" "$@"
