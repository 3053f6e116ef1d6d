#!/usr/bin/env bash
# The batched-engine benchmarks in one command: set up and build with the benchmarks, run the whole-step
# sweep (NovaPhy float64/float32 against MuJoCo 2.2.2, 1..16384 worlds, one thread and all) and the
# kernel benchmark (CRBA + fused Cholesky GFLOP/s against the measured FMA peak), then write the tables
# and the plot.
#   bash tools/bench.sh [extra Google Benchmark options, e.g. --benchmark_repetitions=3]
# Repetitions run in random order across all the benchmarks of a program (Google Benchmark's random
# interleaving), so that a slow spell of this shared machine spreads over NovaPhy's and MuJoCo's lines
# alike instead of landing on whichever ran then; the tables quote medians.
# Output: bench/results/bench_step.json, bench_batch.json, bench.md, bench.png
set -euo pipefail
cd "$(dirname "$0")/.."
# OpenMP threads pinned one to a core, for both engines' loops (unset, the scheduler moved them and the
# two-thread lines of either engine came out up to a third low in some repetitions)
export OMP_PROC_BIND="${OMP_PROC_BIND:-close}" OMP_PLACES="${OMP_PLACES:-cores}"
bash tools/setup.sh >/dev/null
cmake -S . -B build -DNOVAPHY_BUILD_BENCH=ON >/dev/null
cmake --build build -j"$(nproc)" --target novaphy_bench_step novaphy_bench_batch >/dev/null
mkdir -p bench/results
./build/bench/novaphy_bench_step --benchmark_enable_random_interleaving=true --benchmark_out=bench/results/bench_step.json \
  --benchmark_out_format=json "$@"
./build/bench/novaphy_bench_batch --benchmark_enable_random_interleaving=true --benchmark_out=bench/results/bench_batch.json \
  --benchmark_out_format=json "$@"
/usr/bin/python3 tools/bench_report.py bench/results/bench_step.json bench/results/bench_batch.json --out bench/results/bench
