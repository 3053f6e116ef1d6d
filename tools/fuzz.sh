#!/usr/bin/env bash
# Builds the libFuzzer targets (clang-14, ASan + UBSan) in ./build-fuzz and runs each for SECONDS
# (default 60), keeping its corpus in build-fuzz/corpus/<target>. A finding (a crash, or an input that runs past
# 30 s) stops the run with the input written next to the corpus; add it as a regression test.
#   bash tools/fuzz.sh            # 60 s per target, as CI does
#   bash tools/fuzz.sh 3600       # an hour per target
# The runs start from seed 1 (NOVAPHY_FUZZ_SEED to change it), so CI replays the start of what a
# longer local run has already covered.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -DNOVAPHY_FUZZ=ON -DNOVAPHY_BUILD_PYTHON=OFF \
  -DNOVAPHY_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target fuzz_builder fuzz_mjcf
cd build-fuzz  # MuJoCo writes MUJOCO_LOG.TXT into the working directory
for target in fuzz_builder fuzz_mjcf; do
  mkdir -p "corpus/$target" "findings/$target"
  echo "fuzzing $target for $seconds s"
  # libFuzzer reports on stderr; MuJoCo's parser warnings (stdout) are dropped
  "tests/fuzz/$target" -max_total_time="$seconds" -timeout=30 -seed="${NOVAPHY_FUZZ_SEED:-1}" -print_final_stats=1 \
    -artifact_prefix="findings/$target/" \
    "corpus/$target" 2>&1 >/dev/null | tail -n 15
done
