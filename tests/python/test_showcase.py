"""tools/novaphy_showcase, the main job's program (tools/run.sh), end to end on tiny runs: both engines'
robot-steps/s, the robots' centres of mass in each, the validation line and the picture of a few worlds."""

import os
import re
import subprocess

import numpy as np
import pytest
from PIL import Image

BUILD = os.environ.get("NOVAPHY_BUILD_DIR")
pytestmark = pytest.mark.skipif(BUILD is None, reason="needs NOVAPHY_BUILD_DIR (ctest sets it)")
SCENES = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "scenes")
PANEL_WIDTH, PANEL_HEIGHT, GUTTER = 280, 210, 4  # tools/showcase.cpp's layout


def showcase(tmp_path, *args):
    picture = tmp_path / "worlds.png"
    run = subprocess.run([os.path.join(BUILD, "tools", "novaphy_showcase"), *args, "--picture", str(picture),
                          "--no-progress"], capture_output=True, text=True, timeout=600)
    return run, picture


def rates(out):
    """engine -> (worlds, robot-steps/s) from the table"""
    rows = re.findall(r"^(NovaPhy|MuJoCo 2\.2\.2)\s+(\d+)\s+[\d.]+\s+([\d,]+)$", out, re.M)
    return {engine: (int(worlds), int(rate.replace(",", ""))) for engine, worlds, rate in rows}


def panels(picture, rows, columns):
    """the picture as an array, checked to hold rows x columns panels, and each panel's pixels"""
    image = np.asarray(Image.open(picture).convert("RGB")).astype(int)
    assert image.shape == (rows * (PANEL_HEIGHT + GUTTER) + GUTTER, columns * (PANEL_WIDTH + GUTTER) + GUTTER, 3)
    top = [GUTTER + r * (PANEL_HEIGHT + GUTTER) for r in range(rows)]
    left = [GUTTER + c * (PANEL_WIDTH + GUTTER) for c in range(columns)]
    return [[image[y:y + PANEL_HEIGHT, x:x + PANEL_WIDTH] for x in left] for y in top]


def coloured(panel):
    """pixels of a body's colour: the floor, the sky and the gutters are grey"""
    return int(((panel.max(axis=2) - panel.min(axis=2)) > 40).sum())


def test_quadrupeds_in_both_engines_and_a_picture(tmp_path):
    run, picture = showcase(tmp_path, "--worlds", "6", "--steps", "40", "--mujoco-worlds", "3", "--states", "3")
    assert run.returncode == 0, run.stdout + run.stderr
    out = run.stdout
    assert out.startswith("novaphy_showcase: quadruped.xml, 6 worlds of 13 bodies and 18 dofs, 40 steps of 5 ms")
    r = rates(out)
    assert r["NovaPhy"][0] == 6 and r["MuJoCo 2.2.2"][0] == 3
    assert r["NovaPhy"][1] > 0 and r["MuJoCo 2.2.2"][1] > 0
    assert "NovaPhy / MuJoCo 2.2.2: " in out
    # 0.2 s after the same hop in both engines, the robots are still in the air: nearly the same heights
    nova, mujoco = map(float, re.search(r"mean over worlds 0-2: NovaPhy ([\d.]+) m, MuJoCo ([\d.]+) m", out).groups())
    assert nova > 0.3 and abs(nova - mujoco) < 0.01
    assert "NovaPhy worlds flagged diverged: 0 of 6" in out
    worst = re.search(r"largest relative difference NovaPhy vs MuJoCo 2\.2\.2: (\S+) \(within 1e-9\)", out)
    assert worst and float(worst.group(1)) < 1e-9
    assert "quadruped.xml, humanoid.xml, chain15.xml" in out
    assert f"picture: {picture} (rows: worlds 0, 2, 4; columns: t = 0, 0.015, 0.05, 0.115, 0.2 s)" in out
    grid = panels(picture, 3, 5)
    for row in grid:
        assert all(coloured(p) > 2000 for p in row)  # a robot in every panel
        assert np.abs(row[0] - row[-1]).sum() > 0  # that moved
    assert np.abs(grid[0][-1] - grid[1][-1]).sum() > 0  # each world its own way


def test_another_file_without_mujoco(tmp_path):
    run, picture = showcase(tmp_path, os.path.join(SCENES, "chain15.xml"), "--worlds", "2", "--steps", "10",
                            "--mujoco-worlds", "0", "--states", "0", "--frames", "2", "--kick", "0")
    assert run.returncode == 0, run.stdout + run.stderr
    assert list(rates(run.stdout)) == ["NovaPhy"]
    assert "validation" not in run.stdout and "random joint velocities" not in run.stdout
    grid = panels(picture, 2, 2)
    assert all(coloured(p) > 200 for row in grid for p in row)
    assert np.array_equal(grid[0][1], grid[1][1])  # at rest, both worlds fall alike


def test_bad_arguments_are_named(tmp_path):
    for args, message in ((["--worlds", "0"], "--worlds must be >= 1"), (["--frames", "1"], "--frames must be >= 2"),
                          (["--bogus"], "unknown argument '--bogus'"),
                          ([str(tmp_path / "missing.xml")], "missing.xml")):
        run, picture = showcase(tmp_path, *args)
        assert run.returncode == 2 and message in run.stderr, (args, run.stderr)
        assert not picture.exists()
