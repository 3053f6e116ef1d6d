"""Elements of MuJoCo models that change how real robots move, each against today's MuJoCo (PyPI) on an MJCF
written here: solimp values outside MuJoCo's ranges (which it clamps where it reads them)."""

import os

import numpy as np
import pytest

import novaphy

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh installs it in build/venv)"
)


def both(xml, tmp_path, steps):
    """today's MuJoCo and NovaPhy (from_mujoco, SolverFeatherstone) step the model `steps` times from qpos0:
    their final qpos"""
    path = tmp_path / "model.xml"
    path.write_text(xml)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_step(m, d, steps)
    builder = novaphy.ModelBuilder()
    imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    state, control = model.state(), model.control()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
    return d.qpos.copy(), imported.to_qpos(np.array(state.joint_q))


# a 1 kg box resting on the floor on its own solimp: (2, 1, ...) is Trossen's finger pads' (dmin and dmax clamped to
# 0.9999), (0.2, 0.9, 0.05, 1.5, 0.5) has a midpoint above 1 and a power below 1 (clamped to 0.9999 and 1)
@pytest.mark.parametrize("solimp", ["2 1 0.01 0.5 2", "0.2 0.9 0.05 1.5 0.5", "0.3 0.8 -0.1 0.5 2"])
def test_a_solimp_outside_mujocos_ranges_is_clamped_as_mujoco_clamps_it(tmp_path, solimp):
    xml = f"""<mujoco><worldbody><geom type="plane" size="1 1 0.1"/>
      <body pos="0 0 0.1"><freejoint/><geom type="box" size="0.1 0.1 0.1" mass="1" solimp="{solimp}"/></body>
    </worldbody></mujoco>"""
    expected, got = both(xml, tmp_path, 500)
    # the box sinks to where its impedance holds its weight: the same depth as MuJoCo's
    assert abs(got[2] - expected[2]) < 1e-6, (got[2], expected[2])


def shared_robot(name, file):
    """the path of a robot's scene among the Menagerie robots on disk (MENAGERIE_ROOT: ../shared/robots by default
    in the ctest run), else the test is skipped"""
    root = os.environ.get("MENAGERIE_ROOT", "")
    path = os.path.join(root, name, file)
    if not root or not os.path.isfile(path):
        pytest.skip(f"{name} is not on disk (MENAGERIE_ROOT)")
    return path


def contact_bodies(model, state, names):
    """the pairs of body names NovaPhy's collision finds at the state (the world: 'world')"""
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    novaphy.eval_fk(model, state)
    pipeline.collide(state, contacts)
    a, b = np.array(contacts.contact_body_a), np.array(contacts.contact_body_b)
    name = lambda i: names[i] if i >= 0 else "world"  # noqa: E731
    return {tuple(sorted((name(a[i]), name(b[i])))) for i in range(contacts.contact_count)}


# Allegro's fingertips are bodies welded to their medial links: MuJoCo counts a tip as its medial link, so the two
# never meet; without that rule NovaPhy found three tip-medial contacts at the hand's start
def test_welded_fingertips_meet_what_mujocos_filter_lets_them_meet():
    m = mujoco.MjModel.from_xml_path(shared_robot("wonik_allegro", "scene_right.xml"))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    expected = {
        tuple(sorted((m.body(m.geom_bodyid[c.geom1]).name, m.body(m.geom_bodyid[c.geom2]).name)))
        for c in d.contact[: d.ncon]
    }
    builder = novaphy.ModelBuilder()
    imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    state = model.state()
    state.joint_q[:] = imported.to_joint_q(d.qpos)
    names = [n if n else "world" for n in model.body_name]
    assert contact_bodies(model, state, names) == expected
