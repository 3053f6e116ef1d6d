#!/usr/bin/env bash
# Every test: set up and build, then
#   1. ctest in ./build: GoogleTest, the binding's pytest suite, formatting, the installed-package
#      consumer and an offline pip install;
#   2. the C++ tests again under AddressSanitizer + UndefinedBehaviorSanitizer in ./build-asan;
#   3. each libFuzzer target for 60 s (tools/fuzz.sh);
#   4. the training example's smoke test: two PPO iterations of 32 Go1 worlds (tools/train_go1.py, its optional
#      extra from tools/setup_train.sh; skipped, saying so, where PyPI is out of reach or no Menagerie Go1 is on
#      disk), and the float32 arrays' tests again with that extra's JAX (DLPack without a copy).
set -euo pipefail
cd "$(dirname "$0")/.."
# the tests run side by side (-j): their OpenMP threads sleep while they wait rather than spin, so
# one test's team does not take the cores (or a CPU quota) from another's
export OMP_WAIT_POLICY=passive
bash tools/setup.sh
(cd build && ctest --output-on-failure -j"$(nproc)")

cmake -S . -B build-asan -DNOVAPHY_SANITIZE=ON -DNOVAPHY_BUILD_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build-asan -j"$(nproc)" --target novaphy_tests  # all that ctest runs there
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$(nproc)" -E "clang_format|install_consumer")

bash tools/fuzz.sh 60

# the Go1 the smoke test trains (where novaphy.envs.go1_scene looks: NOVAPHY_GO1_SCENE, ../shared/robots beside this
# checkout, the mujoco_menagerie package's copy on disk)
go1_found() {
  [ -n "${NOVAPHY_GO1_SCENE:-}" ] || [ -f ../shared/robots/unitree_go1/scene.xml ] ||
    build/venv/bin/python -c "import sys, mujoco_menagerie as m; r = m.Cache().root
sys.exit(not (r is not None and (r / 'unitree_go1' / 'scene.xml').is_file()))" 2>/dev/null
}
if ! go1_found; then
  echo "novaphy test: no Menagerie Go1 found (../shared/robots beside this checkout, NOVAPHY_GO1_SCENE or the" \
    "mujoco_menagerie package's copy): the training smoke test is skipped"
elif bash tools/setup_train.sh; then
  PYTHONPATH=build/python build/venv-train/bin/python tools/train_go1.py --iterations 2 --worlds 32 --horizon 8 \
    --eval-worlds 4 --eval-seconds 0.2 --gif-seconds 0.2 --out build/train_smoke
  test -s build/train_smoke/summary.json && test -s build/train_smoke/curve.png && test -s build/train_smoke/walk.gif
  PYTHONPATH=build/python build/venv-train/bin/python -m pytest -q tests/python/test_float32.py
else
  echo "novaphy test: the training extra could not be installed (PyPI out of reach?): its smoke test is skipped"
fi
