#!/usr/bin/env bash
# Two builds of NovaPhy side by side: BM_PairedStep (NovaPhy against MuJoCo 2.2.2 at 4096 worlds, all
# cores) for every scene and precision, the two builds' programs alternating before, after, after, before
# on each line, so that a slow spell of the machine lands on both. Each build is a build folder configured
# with -DNOVAPHY_BUILD_BENCH=ON (e.g. a git worktree of the commit before a change, built).
#   bash tools/bench_ab.sh BEFORE_BUILD AFTER_BUILD OUT_DIR [rounds]
# Writes OUT_DIR/{before,after}_s<scene>_p<precision>_<n>.json; tools/bench_ab_report.py makes the table.
set -euo pipefail
before=$1 after=$2 out=$3 rounds=${4:-1}
export OMP_PROC_BIND="${OMP_PROC_BIND:-close}" OMP_PLACES="${OMP_PLACES:-cores}"
mkdir -p "$out"
n=0
for ((round = 0; round < rounds; ++round)); do
  for scene in 0 1 2 3 4; do
    for precision in 0 1; do
      for side in before after after before; do
        build=$before
        [ "$side" = after ] && build=$after
        n=$((n + 1))
        "$build/bench/novaphy_bench_step" --benchmark_filter="BM_PairedStep/scene:$scene/precision:$precision/" \
          --benchmark_format=json > "$out/${side}_s${scene}_p${precision}_$n.json"
      done
    done
  done
done
