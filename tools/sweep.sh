#!/usr/bin/env bash
# The speed/accuracy sweep of one scene in one command: set up and build, run novaphy_sweep, then
# write the markdown table and the Pareto plot beside the CSV.
#   bash tools/sweep.sh SCENE [novaphy_sweep options]     SCENE: chain15 | quadruped | grid | FILE.xml
# Output: bench/results/sweep_<name>.csv, .md, .png (--out PREFIX puts them elsewhere)
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh >/dev/null
scene="${1:?usage: bash tools/sweep.sh SCENE [options]}"
shift
name="$(basename "${scene%.*}")"
prefix="bench/results/sweep_${name}"
args=("$@")
for ((k = 0; k < ${#args[@]}; ++k)); do
  [ "${args[k]}" = "--out" ] && prefix="${args[k + 1]}"
done
mkdir -p "$(dirname "$prefix")"
./build/tools/novaphy_sweep --scene "$scene" --out "$prefix" "$@"
/usr/bin/python3 tools/sweep_report.py "$prefix.csv"
