"""python3 pip_install_check.py SOURCE WORK: pip-installs SOURCE into WORK/site offline and uses it."""

import os
import shutil
import subprocess
import sys

source, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
site = os.path.join(work, "site")
subprocess.check_call(
    [sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--no-index", "--quiet",
     "--target", site, source]
)
check = """
import novaphy, numpy as np
assert novaphy.__file__.startswith({site!r}), novaphy.__file__
builder = novaphy.ModelBuilder()
body = builder.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1])))
builder.add_joint_revolute(-1, body, axis=[0, 0, 1])
H = novaphy.eval_mass_matrix(builder.finalize(), builder.finalize().state())
assert abs(H[0, 0] - (0.2 ** 2 + 1.0) / 12) < 1e-12
print("pip-installed novaphy works:", novaphy.__file__)
""".format(site=site)
subprocess.check_call([sys.executable, "-c", check], env={**os.environ, "PYTHONPATH": site}, cwd=work)
