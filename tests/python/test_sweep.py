"""tools/novaphy_sweep and tools/sweep_report.py end to end on short runs: the CSV, the table and the plot,
and what the numbers must show (first-order convergence in dt, agreement with MuJoCo's RK4, deeper
penetration at larger dt)."""

import csv
import os
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
BUILD = os.environ.get("NOVAPHY_BUILD_DIR")
pytestmark = pytest.mark.skipif(BUILD is None, reason="needs NOVAPHY_BUILD_DIR (ctest sets it)")


def sweep(tmp_path, scene, seconds):
    prefix = str(tmp_path / scene)
    subprocess.run([os.path.join(BUILD, "tools", "novaphy_sweep"), "--scene", scene, "--seconds", seconds,
                    "--out", prefix, "--no-progress"], check=True, capture_output=True)
    with open(prefix + ".csv", newline="") as f:
        rows = {r["setting"]: r for r in csv.DictReader(f)}
    report = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "sweep_report.py"), prefix + ".csv"],
                            check=True, capture_output=True, text=True)
    return rows, prefix, report.stdout


def test_chain_sweep_converges_in_dt_and_matches_mujoco_rk4(tmp_path):
    rows, prefix, out = sweep(tmp_path, "chain15", "0.5,1")
    assert len(rows) == 28 and "Pareto front" in out
    ref = rows["reference"]
    assert float(ref["error_0.5s"]) == 0 and float(ref["mujoco_rk4_error_0.5s"]) < 1e-3
    e = [float(rows[f"dt 1/{n} it 20"]["error_0.5s"]) for n in (120, 240, 480)]
    assert e[0] > 1.5 * e[1] > 2.25 * e[2] > 0  # first order: halving dt about halves the error
    assert float(rows["H every 4 steps"]["error_0.5s"]) > float(rows["dt 1/240 it 20"]["error_0.5s"])
    for r in rows.values():
        assert float(r["robot_steps_per_s"]) > 0
        assert float(r["robot_seconds_per_s"]) == pytest.approx(float(r["robot_steps_per_s"]) * float(r["dt"]),
                                                               rel=1e-4)
    with open(prefix + ".md") as f:
        table = f.read().splitlines()
    assert len(table) == 2 + 28 and "✓" in "".join(table)
    assert os.path.getsize(prefix + ".png") > 10_000


def test_quadruped_sweep_measures_penetration(tmp_path):
    rows, _, _ = sweep(tmp_path, "quadruped", "0.5,1")
    coarse, fine = rows["dt 1/60 it 20"], rows["dt 1/480 it 20"]
    assert float(coarse["max_penetration_m"]) > 5 * float(fine["max_penetration_m"]) > 0
    assert coarse["mujoco_rk4_error_1s"] == ""  # contacts: no MuJoCo reference
    assert all(r["diverged_steps"] == "0" for r in rows.values())
    # the PGS tolerance trades error for sweeps: sweeping to a fixed point errs less than stopping at 1e-3 m/s
    fixed, loose = rows["pgs_tolerance 0"], rows["pgs_tolerance 1e-3"]
    assert 0 < float(fixed["error_1s"]) < float(loose["error_1s"])
    assert float(loose["pgs_tolerance"]) == 1e-3


def test_bad_arguments_are_named(tmp_path):
    tool = os.path.join(BUILD, "tools", "novaphy_sweep")
    for args, message in ((["--seconds", "1,0.5"], "--seconds must be increasing"),
                          (["--seconds", "0.01"], "multiple of 1/60 s"),
                          (["--scene", str(tmp_path / "none.xml")], "file does not exist"),
                          (["--bogus"], "unknown argument '--bogus'")):
        result = subprocess.run([tool] + args, capture_output=True, text=True)
        assert result.returncode == 2 and message in result.stderr, (args, result.stderr)
