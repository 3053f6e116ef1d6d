"""Every robot of the installed mujoco-menagerie that is on disk (MENAGERIE_ROOT, or the package's cache): its scene
loads through both routes (today's MuJoCo's compile with add_mujoco_model, the file with add_mjcf), its contact-free
dynamics match today's MuJoCo to 1e-9 with actuators on, and NovaPhy steps it 1 s from its keyframe without
diverging; Go1's two routes step bit for bit alike (the Panda's do not: the two MuJoCo compilers differ in its
inertias, mesh frames and mesh vertices, docs/mjcf.md). A robot's hand on its own (an entry named "hand", as the
Franka gripper) is checked as well. A robot not on disk is skipped, never fetched; without the PyPI packages the
module is skipped."""

import pytest

pytest.importorskip("mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh)")
mujoco_menagerie = pytest.importorskip(
    "mujoco_menagerie", reason="PyPI's mujoco-menagerie is not installed for this interpreter (tools/setup.sh)"
)

from mujoco_checks import menagerie_entries, menagerie_path, menagerie_status  # noqa: E402


@pytest.mark.parametrize("name, entry", menagerie_entries())
def test_menagerie_robot(name, entry):
    path = menagerie_path(name)
    if path is None:
        pytest.skip(f"{name} is not on disk (set MENAGERIE_ROOT, or run `mujoco-menagerie` to fetch it)")
    status = menagerie_status(name, path, mujoco_menagerie.get(name).entry(entry))
    assert status["mjcf"] == "loads"
    assert status["dynamics"] < 1e-9
    assert status["finite"]
    if name == "unitree_go1":  # where MuJoCo 2.2.2's and today's compilers agree, the two routes step alike
        assert status["same_bits"]
