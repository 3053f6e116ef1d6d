#!/usr/bin/env bash
# The thread sweep (BM_ThreadSweep, tools/scaling.sh) on a lent many-core machine that has no Debian packages
# (the tool library's `device`): built here for x86-64-v4 and carried with the shared libraries it needs.
#   bash tools/device_scaling.sh prepare          # here: build-device/ with the binary, its libraries, humanoid.xml
#   bash tools/device_scaling.sh run [filter]     # there, in the copy's root, carry build-device; writes
#                                                 # $OUT/scaling.json (default filter: both precisions, all
#                                                 # three scenes, 1024 to 16384 worlds)
# then here: python3 tools/scaling_report.py scaling.json --out bench/results/scaling_<machine>.md
# The binary reads its scenes at the paths it was built with; `run` links this copy's scenes and the carried
# humanoid.xml there (the machine's root is the caller's).
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  prepare)
    bash tools/setup.sh >/dev/null
    cmake -S . -B build-device -DNOVAPHY_ARCH=x86-64-v4 -DNOVAPHY_BUILD_BENCH=ON >/dev/null
    cmake --build build-device -j"$(nproc)" --target novaphy_bench_step >/dev/null
    mkdir -p build-device/carry/lib
    cp build-device/bench/novaphy_bench_step build-device/carry/
    cp /usr/share/mujoco/model/humanoid/humanoid.xml build-device/carry/
    # every library the binary loads but the C library's own
    ldd build-device/bench/novaphy_bench_step | awk '/=> \// {print $3}' |
      grep -v -E '/(libc|libm|libpthread|libdl|librt|ld-linux[^/]*)\.so' |
      xargs -I{} cp -L {} build-device/carry/lib/
    echo "source root: $PWD" > build-device/carry/SOURCE_ROOT
    du -sh build-device/carry
    ;;
  run)
    carry=build-device/carry
    root=$(sed -n 's/^source root: //p' "$carry/SOURCE_ROOT")
    if [ "$root" != "$PWD" ]; then
      mkdir -p "$root/bench"
      [ -e "$root/bench/scenes" ] || ln -s "$PWD/bench/scenes" "$root/bench/scenes"
    fi
    mkdir -p /usr/share/mujoco/model/humanoid
    [ -e /usr/share/mujoco/model/humanoid/humanoid.xml ] || cp "$carry/humanoid.xml" /usr/share/mujoco/model/humanoid/
    export LD_LIBRARY_PATH="$PWD/$carry/lib" OMP_PROC_BIND=close OMP_PLACES=cores
    out="${OUT:-.}"
    nproc > "$out/cpus.txt"
    lscpu > "$out/lscpu.txt" 2>/dev/null || true
    "$carry/novaphy_bench_step" --benchmark_filter="${2:-BM_ThreadSweep/scene:[123]/precision:[01]/worlds:(1024|4096|16384)/}" \
      --benchmark_out="$out/scaling.json" --benchmark_out_format=json
    ;;
  *)
    echo "usage: bash tools/device_scaling.sh prepare | run [filter]" >&2
    exit 2
    ;;
esac
