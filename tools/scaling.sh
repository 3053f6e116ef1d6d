#!/usr/bin/env bash
# The thread sweep on this machine: NovaPhy (float64 and float32) and MuJoCo 2.2.2 on 1, 2, 4, ... threads and
# all, the contact-free quadruped, the standing quadruped and humanoid.xml at 256, 512, 1024, 4096 and 16384 worlds
# (novaphy_bench_step's BM_ThreadSweep), then the table of speed-ups, parallel efficiency and NovaPhy's serial
# share. Runs on any machine with the build's dependencies; the threads pinned one to a core as in bench.sh.
#   bash tools/scaling.sh [extra Google Benchmark options, e.g. --benchmark_filter=BM_ThreadSweep/scene:1/]
# Output: bench/results/scaling.json and bench/results/scaling.md
set -euo pipefail
cd "$(dirname "$0")/.."
export OMP_PROC_BIND="${OMP_PROC_BIND:-close}" OMP_PLACES="${OMP_PLACES:-cores}"
bash tools/setup.sh >/dev/null
cmake -S . -B build -DNOVAPHY_BUILD_BENCH=ON >/dev/null
cmake --build build -j"$(nproc)" --target novaphy_bench_step >/dev/null
mkdir -p bench/results
./build/bench/novaphy_bench_step --benchmark_filter=BM_ThreadSweep --benchmark_out=bench/results/scaling.json \
  --benchmark_out_format=json "$@"
/usr/bin/python3 tools/scaling_report.py bench/results/scaling.json --out bench/results/scaling.md
