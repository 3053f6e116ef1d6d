"""MuJoCo's soft constraint rows beyond contacts (engine/solver/parts/soft_row.h): joint and tendon limits, dry friction
(frictionloss) and equality constraints, each against today's MuJoCo (PyPI) on an MJCF written here (both import
routes) and on a shared Menagerie robot: the quantity the softness changes (a limit's push-out from a start outside
the range, dry friction's creep under a load, a loop's closing rate), and the hard rows of soft_constraints off."""

import sys
import warnings

import numpy as np
import pytest

import novaphy
from mujoco_checks import by_route, shared_robot

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh installs it in build/venv)"
)


def trajectories(xml, tmp_path, steps, route="from_mujoco", soft=True, batch=True):
    """today's MuJoCo's and NovaPhy's (SolverFeatherstone, soft_constraints `soft`, use_batch_kernels `batch`: the
    blocks' rows or the islands'; the model from today's MuJoCo's compile or the file through add_mjcf) qpos after
    each of `steps` steps from the first keyframe"""
    path = tmp_path / "model.xml"
    path.write_text(xml)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    expected = []
    for _ in range(steps):
        mujoco.mj_step(m, d)
        expected.append(d.qpos.copy())
    imported, model = by_route(m, path, route)
    state = model.state(keyframe=model.keyframes[0])
    control = model.control()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.angular_damping = 0  # (MuJoCo has none)
    solver.settings.soft_constraints = soft
    solver.settings.use_batch_kernels = batch
    solver.settings.num_iterations = ITERATIONS
    solver.settings.pgs_tolerance = 0  # (the sweeps to their fixed point: the comparison is of the model)
    got = []
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
        got.append(imported.to_qpos(np.array(state.joint_q)))
    return np.array(expected), np.array(got)


# the model from today's MuJoCo's compile, stepped by the blocks; the file through add_mjcf, by the islands
ITERATIONS = 20
ROUTES = [("from_mujoco", True), ("add_mjcf", False)]

# a rod on a hinge whose keyframe is 0.26 rad past its upper limit (as Allegro's thumb starts), no gravity
LIMIT_KICK = """<mujoco><compiler angle="radian"/><option gravity="0 0 0"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 0 1" range="-0.5 0.5" {soft}/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="1" contype="0" conaffinity="0"/></body></worldbody>
  <keyframe><key qpos="0.76"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route, batch", ROUTES)
@pytest.mark.parametrize("soft", ["", 'solreflimit="0.05 0.7" solimplimit="0.5 0.9 0.1 0.5 2"'])
def test_a_start_past_a_limit_is_pushed_back_at_mujocos_rate(tmp_path, route, batch, soft):
    expected, got = trajectories(LIMIT_KICK.format(soft=soft), tmp_path, 100, route, batch=batch)
    # the push-out over 0.2 s (MuJoCo's default: 3.8 rad/s after the first step, where a hard row's erp gives 26)
    assert np.max(np.abs(got - expected)) < 1e-6, np.max(np.abs(got - expected))
    assert expected[0, 0] < 0.76 - 1e-4 and expected[-1, 0] < 0.55


def test_hard_rows_kick_a_start_past_a_limit_out_at_the_erp_rate(tmp_path):
    expected, got = trajectories(LIMIT_KICK.format(soft=""), tmp_path, 1, soft=False)
    # one step of the hard row: erp (0.2) of the 0.26 rad beyond the slop in a step of 2 ms, some 26 rad/s
    assert abs((0.76 - got[0, 0]) / 0.002 - 0.2 * (0.26 - 0.001) / 0.002) < 0.1
    assert (0.76 - got[0, 0]) > 10 * (0.76 - expected[0, 0])


# a horizontal rod on a hinge about y under gravity (0.3 kg at 0.15 m: 0.44 N m) against dry friction of 0.3 N m (it
# falls) or 0.6 N m (a hard row holds it still, MuJoCo's soft one lets it creep)
FRICTION = """<mujoco><worldbody><body><joint name="j" type="hinge" axis="0 1 0" frictionloss="{loss}" {soft}/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.3" contype="0" conaffinity="0"/></body>
  </worldbody><keyframe><key qpos="0"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route, batch", ROUTES)
@pytest.mark.parametrize(
    "loss, soft", [(0.6, ""), (0.3, ""), (0.6, 'solreffriction="0.1 1" solimpfriction="0.5 0.8 0.01"')]
)
def test_dry_friction_creeps_as_mujocos(tmp_path, route, batch, loss, soft):
    expected, got = trajectories(FRICTION.format(loss=loss, soft=soft), tmp_path, 500, route, batch=batch)
    assert np.max(np.abs(got - expected)) < 1e-6 * max(1, np.max(np.abs(expected))), np.max(np.abs(got - expected))
    assert abs(expected[-1, 0]) > 1e-4  # (it moved)


def test_hard_dry_friction_holds_what_mujocos_lets_creep(tmp_path):
    expected, got = trajectories(FRICTION.format(loss=0.6, soft=""), tmp_path, 500, soft=False)
    assert abs(got[-1, 0]) < 1e-9 < 1e-4 < abs(expected[-1, 0])


# a pendulum of two links whose tip a connect holds on a point of the world 2 mm from where the keyframe puts it (as
# Cassie's keyframe leaves its loops open): the loop closes at MuJoCo's rate
LOOP = """<mujoco><option gravity="0 0 -9.81"/>
  <worldbody><body name="a"><joint name="j1" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="1" contype="0" conaffinity="0"/>
      <body name="b" pos="0.2 0 0"><joint name="j2" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="1" contype="0" conaffinity="0"/></body></body>
  </worldbody>
  <equality><connect body1="b" body2="world" anchor="0 0 -0.2" {soft}/></equality>
  <keyframe><key qpos="0.0075 0"/></keyframe></mujoco>"""


def loop_gap(qpos):
    """the tip's distance from the world point the connect holds it to (at qpos0: x 0.2, z -0.2)"""
    q1, q2 = qpos[..., 0], qpos[..., 1]
    x = 0.2 * np.cos(q1) + 0.2 * np.sin(q1 + q2)
    z = -0.2 * np.sin(q1) - 0.2 * np.cos(q1 + q2)
    return np.hypot(x - 0.2, z + 0.2)


@pytest.mark.parametrize("route, batch", ROUTES)
@pytest.mark.parametrize("soft", ["", 'solref="0.05 0.5" solimp="0.5 0.99 0.01 0.5 2"'])
def test_a_connects_loop_closes_at_mujocos_rate(tmp_path, route, batch, soft):
    expected, got = trajectories(LOOP.format(soft=soft), tmp_path, 200, route, batch=batch)
    _, hard = trajectories(LOOP.format(soft=soft), tmp_path, 200, route, soft=False, batch=batch)
    gap_mujoco, gap, gap_hard = loop_gap(expected), loop_gap(got), loop_gap(hard)
    # MuJoCo's default closes the 2 mm loop to its sag under gravity (0.3 mm) in 0.1 s, the softer one sags to 4 mm;
    # the hard rows close it to 1e-9 m: a hundred times farther from MuJoCo's than the soft rows are
    assert np.max(np.abs(gap - gap_mujoco)) < 0.005 * gap_mujoco[0], np.max(np.abs(gap - gap_mujoco))
    assert np.max(np.abs(gap_hard - gap_mujoco)) > 100 * np.max(np.abs(gap - gap_mujoco))
    assert gap_hard[-1] < 1e-8


# two hinges a joint equality couples (q1 = q2), started 0.1 rad apart; and a fixed tendon over them whose keyframe is
# past its upper limit
COUPLING = """<mujoco><option gravity="0 0 0"/>
  <worldbody>
    <body><joint name="j1" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="1" contype="0" conaffinity="0"/></body>
    <body pos="1 0 0"><joint name="j2" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.02" mass="2" contype="0" conaffinity="0"/></body>
  </worldbody>
  {element}
  <keyframe><key qpos="0.1 0"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route, batch", ROUTES)
@pytest.mark.parametrize(
    "element",
    [
        '<equality><joint joint1="j1" joint2="j2"/></equality>',
        '<equality><joint joint1="j1" joint2="j2" solref="0.1 0.3"/></equality>',
        '<tendon><fixed name="t" range="-0.05 0.05" limited="true"><joint joint="j1" coef="1"/>'
        '<joint joint="j2" coef="-1"/></fixed></tendon>',
    ],
)
def test_a_coupling_and_a_tendon_limit_pull_in_at_mujocos_rate(tmp_path, route, batch, element):
    expected, got = trajectories(COUPLING.format(element=element), tmp_path, 100, route, batch=batch)
    assert np.max(np.abs(got - expected)) < 1e-6, np.max(np.abs(got - expected))
    assert abs(expected[-1, 0] - expected[-1, 1]) < 0.09  # (it moved)


def test_soft_rows_read_the_models_softness_and_weights():
    xml = LIMIT_KICK.format(soft='solreflimit="0.05 0.7" solimplimit="0.5 0.9 0.1 0.5 2"')
    m = mujoco.MjModel.from_xml_string(xml)
    model = novaphy.from_mujoco(m)
    assert list(model.joint_limit_solref.ravel()) == [0.05, 0.7]
    assert list(model.joint_limit_solimp.ravel()) == [0.5, 0.9, 0.1, 0.5, 2]
    assert list(model.joint_friction_solref.ravel()) == list(m.dof_solref[0])
    # MuJoCo's dof_invweight0: M^-1's diagonal at qpos0
    assert abs(model.joint_invweight0[0] - m.dof_invweight0[0]) < 1e-12 * m.dof_invweight0[0]


def test_a_builders_rows_are_hard_until_given_a_solref():
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]))
    dof = novaphy.JointDofConfig()
    dof.axis = [0, 0, 1]
    dof.limit_lower, dof.limit_upper = -0.5, 0.5
    b.add_joint_revolute(-1, body, axis=dof)
    model = b.finalize()
    assert list(model.joint_limit_solref.ravel()) == [0, 0] and model.joint_invweight0[0] == 0
    dof.limit_solref = [0.02, 1]
    b2 = novaphy.ModelBuilder()
    b2.add_joint_revolute(-1, b2.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1])), axis=dof)
    assert b2.finalize().joint_invweight0[0] > 0


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("limit_solref", [0.02, -1], "limit_solref must be"),
        ("friction_solref", [float("nan"), 1], "friction_solref must be"),
        ("limit_solimp", [0.9, 0.95, float("inf"), 0.5, 2], "limit_solimp must be five finite numbers"),
    ],
)
def test_a_bad_softness_is_refused_naming_the_joint(field, value, message):
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]))
    dof = novaphy.JointDofConfig()
    setattr(dof, field, value)
    with pytest.raises(ValueError, match=f"joint 0 \\('hinge'\\).*{message}"):
        b.add_joint_revolute(-1, body, axis=dof, name="hinge")


def test_a_bad_equality_softness_is_refused_naming_the_equality():
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]))
    b.add_joint_free(-1, body)
    e = b.add_connect(body, -1, [0, 0, 0], name="loop")
    with pytest.raises(ValueError, match="equality 0 \\('loop'\\): solref must be"):
        b.set_equality_softness(e, [-1, 1])
    with pytest.raises(ValueError, match="set_equality_softness: equality 3 out of range"):
        b.set_equality_softness(3, [0.02, 1])


def test_a_mixed_solref_is_mujocos_default_with_a_warning():
    xml = LIMIT_KICK.format(soft='solreflimit="0.05 -1"')
    m = mujoco.MjModel.from_xml_string(xml)
    with pytest.warns(UserWarning, match="joint 'j' solreflimit .* mixes MuJoCo's two formats"):
        model = novaphy.from_mujoco(m)
    assert list(model.joint_limit_solref.ravel()) == [0.02, 1]


def test_allegros_thumb_is_pushed_into_its_range_at_mujocos_rate():
    m = mujoco.MjModel.from_xml_path(shared_robot("wonik_allegro", "scene_right.xml"))
    # its joints' damping and its position actuators out: NovaPhy integrates both implicitly, so they enter the rows'
    # effective mass, where MuJoCo's Euler step solves its rows without them (docs/step.md, Soft rows)
    m.dof_damping[:] = 0
    m.actuator_gainprm[:] = 0
    m.actuator_biasprm[:] = 0
    lower = [j for j in range(m.njnt) if m.jnt_limited[j] and m.qpos0[m.jnt_qposadr[j]] < m.jnt_range[j][0]]
    assert len(lower) == 1  # (qpos0 0 below the thumb's first joint's range [0.263, 1.396])
    thumb = m.jnt_qposadr[lower[0]]
    d = mujoco.MjData(m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        builder = novaphy.ModelBuilder()
        imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    got = {}
    for soft in (True, False):
        state, pipeline = model.state(), novaphy.CollisionPipeline(model)
        contacts = pipeline.contacts()
        solver = novaphy.solvers.SolverFeatherstone(model)
        solver.settings.angular_damping = 0
        solver.settings.soft_constraints = soft
        for _ in range(10):
            pipeline.collide(state, contacts)
            solver.step(state, state, model.control(), contacts, m.opt.timestep)
        got[soft] = imported.to_qpos(np.array(state.joint_q))
    mujoco.mj_step(m, d, 10)
    # pushed in by 0.08 rad in 20 ms, to 1e-9 of MuJoCo's; the hard rows' erp pushes it farther
    assert d.qpos[thumb] > 0.05
    assert np.max(np.abs(got[True] - d.qpos)) < 1e-9, np.max(np.abs(got[True] - d.qpos))
    assert got[False][thumb] - d.qpos[thumb] > 0.05, got[False][thumb]


# a box welded to the world at MuJoCo's default softness, its weld's anchor the world's origin 2.2 m away (MuJoCo's
# default anchor): the soft weld sags and swings the box down and out, as MuJoCo's
WELD = """<mujoco><worldbody>
  <body name="hung" pos="1 0 2"><freejoint/>
    <geom type="box" size="0.05 0.05 0.05" mass="1" contype="0" conaffinity="0"/></body></worldbody>
  <equality><weld body1="hung"/></equality><keyframe><key qpos="1 0 2 1 0 0 0"/></keyframe></mujoco>"""


def test_a_soft_weld_to_the_world_swings_as_mujocos(tmp_path, monkeypatch):
    # (its six rows coupled through the 2.2 m lever: the sweeps converge slowly)
    monkeypatch.setattr(sys.modules[__name__], "ITERATIONS", 2000)
    expected, got = trajectories(WELD, tmp_path, 500)
    assert np.max(np.abs(got[:50, :3] - expected[:50, :3])) < 1e-5  # the first 0.1 s, to 10 µm
    assert np.max(np.abs(got[:, :3] - expected[:, :3])) < 0.03  # 1 s: down 1.5 m, as MuJoCo's to 3 cm
    assert expected[-1, 2] < 1


# the two rods of COUPLING spun apart (2 rad/s) against a fixed tendon's dry friction over them: the friction slows
# their relative motion, softly as MuJoCo's
TENDON_FRICTION = COUPLING.replace('<key qpos="0.1 0"/>', '<key qpos="0 0" qvel="2 0"/>')


@pytest.mark.parametrize("route, batch", ROUTES)
@pytest.mark.parametrize("soft", ["", 'solreffriction="0.05 1" solimpfriction="0.5 0.8 0.01"'])
def test_a_tendons_dry_friction_slows_it_as_mujocos(tmp_path, route, batch, soft):
    element = (
        f'<tendon><fixed name="t" frictionloss="0.002" {soft}><joint joint="j1" coef="1"/>'
        '<joint joint="j2" coef="-1"/></fixed></tendon>'
    )
    expected, got = trajectories(TENDON_FRICTION.format(element=element), tmp_path, 200, route, batch=batch)
    assert np.max(np.abs(got - expected)) < 1e-6, np.max(np.abs(got - expected))
    no_friction, _ = trajectories(TENDON_FRICTION.format(element=""), tmp_path, 200, route, batch=batch)
    assert np.max(np.abs(no_friction - expected)) > 0.01  # (the friction changes the motion)


@pytest.mark.parametrize(
    "keywords, message",
    [
        ({"frictionloss": -1.0}, "frictionloss must be finite and >= 0"),
        ({"friction_solref": [1, -1]}, "friction_solref"),
    ],
)
def test_a_bad_tendon_friction_is_refused_naming_the_tendon(keywords, message):
    b = novaphy.ModelBuilder()
    joints = []
    for _ in range(2):
        body = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]))
        joints.append(b.add_joint_revolute(-1, body, axis=[0, 0, 1]))
    with pytest.raises(ValueError, match=f"tendon 0 \\('t'\\): {message}"):
        b.add_tendon(joints, [1.0, -1.0], name="t", **keywords)
