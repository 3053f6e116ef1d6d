#!/usr/bin/env bash
# The optional peer of bench/newton_compare.py: NVIDIA Newton and warp-lang from PyPI in build/venv-newton, a virtual
# environment of Debian's /usr/bin/python3 that sees Debian's packages (so the module built for that interpreter
# imports beside Newton in one process, and numpy stays Debian's: --no-deps, pinned). About 500 MB (warp's
# libraries); nothing but the comparison needs it. Runs tools/setup.sh first; safe to run again; exits 1 where PyPI
# is out of reach.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
pypi=(newton==1.8.0 warp-lang==1.19.0)
if [ ! -x build/venv-newton/bin/python ] || ! build/venv-newton/bin/python -c "import newton, warp" 2>/dev/null; then
  /usr/bin/python3 -m venv --system-site-packages build/venv-newton
  build/venv-newton/bin/pip install -q --disable-pip-version-check --no-deps "${pypi[@]}"
fi
