#!/usr/bin/env bash
# Installs the Debian packages NovaPhy needs (only those missing), then configures and builds it
# in ./build (Release). Used by run.sh and test.sh; safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake g++ make libeigen3-dev libgtest-dev libbenchmark-dev libmujoco-dev libmujoco-samples libtinyxml2-dev libccd-dev libqhull-dev
          pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-pil python3-tqdm
          python3-setuptools python3-pip python3-venv clang-format clang-14 libclang-rt-14-dev libomp-14-dev
          libopenmpi-dev openmpi-bin python3-mpi4py python3-typing-extensions python3-cloudpickle)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "novaphy setup: installing ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# today's MuJoCo and Menagerie, and Gymnasium (novaphy.envs), from PyPI (what Debian lacks) in build/venv, a
# virtual environment of Debian's
# /usr/bin/python3 that sees Debian's packages: the module built for that interpreter imports in it, and numpy
# stays Debian's (--no-deps: PyPI's numpy 2 would shadow it). Best effort: without PyPI, the tests that need
# them are skipped
pypi=(mujoco==4.0.0 mujoco-core==4.0.0 mujoco-menagerie==2026.10.4 gymnasium==1.4.0 farama-notifications==0.0.6)
if [ ! -x build/venv/bin/python ] || ! build/venv/bin/python -c "import mujoco, mujoco_menagerie, gymnasium" 2>/dev/null; then
  /usr/bin/python3 -m venv --system-site-packages build/venv
  build/venv/bin/pip install -q --disable-pip-version-check --no-deps "${pypi[@]}" ||
    echo "novaphy setup: PyPI is out of reach: ${pypi[*]} not installed; their tests will be skipped"
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 -DNOVAPHY_WITH_MPI=ON >/dev/null
cmake --build build -j"$(nproc)"
