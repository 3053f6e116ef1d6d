"""tools/stream_threshold.py on a short run: one line a world count, the step's data it reports equal to
the solver's memory and the state's arrays, and a ratio of two positive times."""

import os
import re
import subprocess
import sys

import novaphy

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")


def test_stream_threshold_reports_each_world_count(scene):
    out = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "stream_threshold.py"), "--worlds", "16,48",
                          "--precision", "Float64", "--rounds", "2"], check=True, capture_output=True, text=True).stdout
    lines = re.findall(r"^ *(\d+) worlds Float64, ([\d.]+) MB: streamed/stored ([\d.]+) ", out, re.M)
    assert [int(w) for w, _, _ in lines] == [16, 48]
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(scene("quadruped.xml"))
    for worlds, megabytes, ratio in lines:
        batch = novaphy.ModelBuilder()
        batch.replicate(robot, int(worlds))
        model = batch.finalize()
        state = model.state()
        arrays = (state.joint_q, state.joint_qd, state.body_q, state.body_qd, state.body_f)
        data = novaphy.solvers.SolverFeatherstone(model).memory_bytes + sum(a.nbytes for a in arrays)
        assert float(megabytes) == round(data / 1e6, 1)
        assert float(ratio) > 0


def test_stream_threshold_names_a_bad_argument():
    for args, culprit in ((["--rounds", "1"], "--rounds 1"), (["--worlds", "16,x"], "--worlds")):
        run = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "stream_threshold.py"), *args],
                             capture_output=True, text=True)
        assert run.returncode != 0 and culprit in run.stderr
