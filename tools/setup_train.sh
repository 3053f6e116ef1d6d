#!/usr/bin/env bash
# The optional training extra of tools/train_go1.py (PPO on the Go1 environment): JAX and optax from PyPI in
# build/venv-train, a virtual environment of Debian's /usr/bin/python3 that sees Debian's packages, so the module
# built for that interpreter imports in it and numpy and scipy stay Debian's (--no-deps, pinned: PyPI's numpy 2
# would shadow numpy 1.24, which the module's pybind11 is built for). Nothing but the training example needs it.
# Runs tools/setup.sh first; safe to run again; exits 1 where PyPI is out of reach.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
if ! dpkg-query -W -f='${Status}' python3-scipy 2>/dev/null | grep -q "install ok installed"; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends python3-scipy >/dev/null
fi
pypi=(jax==0.4.30 jaxlib==0.4.30 optax==0.2.3 chex==0.1.90 ml_dtypes==0.5.4 opt_einsum==3.4.0 absl-py==2.5.1
      toolz==1.2.0 etils==1.15.0 typing_extensions==4.16.0 gymnasium==1.4.0 farama-notifications==0.0.6)
if [ ! -x build/venv-train/bin/python ] || ! build/venv-train/bin/python -c "import jax, optax, gymnasium" 2>/dev/null; then
  /usr/bin/python3 -m venv --system-site-packages build/venv-train
  build/venv-train/bin/pip install -q --disable-pip-version-check --no-deps "${pypi[@]}"
fi
