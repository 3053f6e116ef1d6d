"""Spatial tendons (engine/model/spatial_tendon.h: MuJoCo's <spatial>, through sites, around spheres and cylinders
with and without side sites, past pulleys), each against today's MuJoCo (PyPI) on MJCF written here, both import
routes: their lengths and velocities at random poses, the forces of their springs, dampers and actuators, a limit
holding a box as a rope, and the shared Robotiq scene's hanging box; bad paths refused by name."""

import numpy as np
import pytest

import novaphy
from mujoco_checks import by_route, largest_dynamics_difference, random_state, shared_robot

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh installs it in build/venv)"
)

ROUTES = ["from_mujoco", "add_mjcf"]

# a two-link arm turning in 3D, a wheel (cylinder) at its elbow and a ball (sphere) on its forearm, a free box; the
# tendons: straight through three sites, around the wheel on its side site's side, around the ball the shorter way,
# around the ball from inside (a side site within it), and past a pulley to the box (two articulations)
ARM = """<mujoco><compiler angle="radian"/><option timestep="0.002"/>
  <worldbody>
    <site name="anchor" pos="0 0 0.5"/>
    <body name="upper">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.05"/>
      <joint name="twist" type="hinge" axis="1 0 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.02" mass="1" contype="0" conaffinity="0"/>
      <geom name="wheel" type="cylinder" pos="0.4 0 0" size="0.05 0.02" euler="1.5707963 0 0" mass="0"
            contype="0" conaffinity="0"/>
      <site name="wheel_side" pos="0.4 0 0.1"/>
      <site name="upper_site" pos="0.2 0 0.03"/>
      <body name="lower" pos="0.4 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.05"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.5" contype="0" conaffinity="0"/>
        <geom name="ball" type="sphere" pos="0.15 0 0" size="0.04" mass="0" contype="0" conaffinity="0"/>
        <site name="lower_site" pos="0.3 0 0.02"/>
        <site name="ball_inside" pos="0.15 0 0.01"/>
      </body>
    </body>
    <body name="box" pos="0.6 0 -0.3">
      <freejoint/>
      <geom type="box" size="0.03 0.03 0.03" mass="0.2" contype="0" conaffinity="0"/>
      <site name="hook" pos="0 0 0.03"/>
    </body>
  </worldbody>
  <tendon>
    <spatial name="straight" stiffness="50" damping="1">
      <site site="anchor"/><site site="upper_site"/><site site="lower_site"/></spatial>
    <spatial name="around_wheel" stiffness="30" damping="0.5">
      <site site="upper_site"/><geom geom="wheel" sidesite="wheel_side"/><site site="lower_site"/></spatial>
    <spatial name="around_ball" stiffness="20">
      <site site="upper_site"/><geom geom="ball"/><site site="lower_site"/></spatial>
    <spatial name="inside_ball" stiffness="10">
      <site site="upper_site"/><geom geom="ball" sidesite="ball_inside"/><site site="lower_site"/></spatial>
    <spatial name="pulley" stiffness="20" damping="0.3">
      <site site="anchor"/><site site="upper_site"/><pulley divisor="2"/><site site="anchor"/><site site="hook"/>
    </spatial>
  </tendon>
  <actuator>
    <motor tendon="straight" gear="2"/>
    <position tendon="around_wheel" kp="40"/>
    <general tendon="pulley" gainprm="3" biasprm="1 -5 -0.5"/>
  </actuator>
  <sensor>
    <tendonpos tendon="straight"/><tendonpos tendon="around_wheel"/><tendonpos tendon="around_ball"/>
    <tendonpos tendon="inside_ball"/><tendonpos tendon="pulley"/>
    <tendonvel tendon="straight"/><tendonvel tendon="around_wheel"/><tendonvel tendon="around_ball"/>
    <tendonvel tendon="inside_ball"/><tendonvel tendon="pulley"/>
  </sensor>
  <keyframe><key qpos="0.3 -0.4 0.8  0.6 0 -0.3 1 0 0 0" ctrl="0.5 0.9 0.2"/></keyframe>
</mujoco>"""


def compiled(xml, tmp_path):
    path = tmp_path / "model.xml"
    path.write_text(xml)
    return mujoco.MjModel.from_xml_path(str(path)), path


@pytest.mark.parametrize("route", ROUTES)
def test_lengths_and_velocities_are_mujocos_at_random_poses(tmp_path, route):
    m, path = compiled(ARM, tmp_path)
    d = mujoco.MjData(m)
    imported, model = by_route(m, path, route)
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    rng = np.random.default_rng(3)
    wrapped = np.zeros(m.ntendon, bool)
    straight = np.zeros(m.ntendon, bool)
    for _ in range(40):
        random_state(m, d, rng)
        d.qpos[: m.jnt_qposadr[3]] *= 3  # (the arm's hinges over +-3 rad: each wrap on and off)
        mujoco.mj_forward(m, d)
        state, out = model.state(), model.state()
        state.joint_q[:] = imported.to_joint_q(d.qpos)
        state.joint_qd[:] = imported.to_joint_qd(d.qpos, d.qvel)
        novaphy.eval_fk(model, state)
        pipeline.collide(state, contacts)
        solver.step(state, out, model.control(), contacts, 1e-4)
        values = np.array(out.sensor_data)  # (the step's start: lengths, then velocities)
        assert np.max(np.abs(values[:5] - d.ten_length)) < 1e-12, (values[:5], d.ten_length)
        # (an inside wrap's point comes from a Newton solve, which MuJoCo 4 made more stable than the one written
        # here: the length is stationary in the point, the direction of its pieces not; 1.1e-9 apart at most here)
        assert np.max(np.abs(values[5:] - d.ten_velocity)) < 1e-8 * max(1, np.max(np.abs(d.ten_velocity)))
        # which wraps bent the path (MuJoCo's wrap points: more than its two sites)
        for t in (1, 2, 3):
            bent = d.ten_wrapnum[t] > 2
            wrapped[t] |= bent
            straight[t] |= not bent
    assert wrapped[1:4].all() and straight[1:4].all(), (wrapped, straight)


def test_spring_damper_and_actuator_forces_are_mujocos_at_random_states(tmp_path):
    m, _ = compiled(ARM, tmp_path)
    # forward dynamics with constraints off and the actuators on, relative to the largest acceleration
    assert largest_dynamics_difference(m, states=20) < 1e-9


@pytest.mark.parametrize("route", ROUTES)
def test_the_arm_moves_as_mujocos_under_its_tendons(tmp_path, route):
    m, path = compiled(ARM, tmp_path)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    imported, model = by_route(m, path, route)
    state = model.state(keyframe=model.keyframes[0])
    control = model.control(keyframe=model.keyframes[0])
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.angular_damping = 0
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    worst = 0.0
    for _ in range(250):
        mujoco.mj_step(m, d)
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
        worst = max(worst, np.max(np.abs(imported.to_qpos(np.array(state.joint_q)) - d.qpos)))
    # 0.5 s of a swing of some 1 rad (MuJoCo's Euler with implicit joint damping: NovaPhy's too)
    assert worst < 1e-6, worst


# a box hung from the world by a tendon of range [0, 0.02] (the shared Robotiq scene's rope), started 2 cm below the
# rope's end and swinging
ROPE = """<mujoco><option timestep="0.002"/>
  <worldbody><site name="anchor" pos="0 0 0.2"/>
    <body name="object" pos="0 0 0.15"><freejoint/>
      <geom type="box" size="0.015 0.015 0.015" mass="0.1" contype="0" conaffinity="0"/>
      <site name="hook" pos="0.015 0.015 0.015"/></body></worldbody>
  <tendon><spatial limited="true" range="0 0.02" {soft}><site site="hook"/><site site="anchor"/></spatial></tendon>
  <keyframe><key qpos="0.01 0 0.15 1 0 0 0"/></keyframe>
</mujoco>"""


@pytest.mark.parametrize("route, batch", [("from_mujoco", True), ("add_mjcf", False)])
@pytest.mark.parametrize("soft", ["", 'solreflimit="0.01 0.5"'])
def test_a_box_hangs_on_a_spatial_tendons_limit_as_mujocos(tmp_path, route, batch, soft):
    m, path = compiled(ROPE.format(soft=soft), tmp_path)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    imported, model = by_route(m, path, route)
    state = model.state(keyframe=model.keyframes[0])
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.angular_damping = 0
    solver.settings.use_batch_kernels = batch
    solver.settings.num_iterations = 20
    solver.settings.pgs_tolerance = 0
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    heights, expected, lengths = [], [], []
    for _ in range(250):
        mujoco.mj_step(m, d)
        pipeline.collide(state, contacts)
        solver.step(state, state, model.control(), contacts, m.opt.timestep)
        heights.append(imported.to_qpos(np.array(state.joint_q))[:3])
        expected.append(d.qpos[:3].copy())
        lengths.append(d.ten_length[0])
    heights, expected = np.array(heights), np.array(expected)
    # pulled in from 2.6 cm past the range (2.2 mm past it after 0.5 s) and swinging 2 cm on the rope
    assert lengths[0] > 0.045 and lengths[-1] < 0.025 and np.ptp(expected[:, 0]) > 0.015
    assert np.max(np.abs(heights - expected)) < 1e-6, np.max(np.abs(heights - expected))


def test_robotiqs_box_hangs_as_in_mujoco():
    path = shared_robot("robotiq_2f85", "scene.xml")
    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    builder = novaphy.ModelBuilder()
    with _no_warning():
        imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    state, control = model.state(), model.control()
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    for _ in range(int(1 / m.opt.timestep)):
        mujoco.mj_step(m, d)
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
    box = m.jnt_qposadr[m.body("object").jntadr[0]]
    got = imported.to_qpos(np.array(state.joint_q))[box : box + 3]
    # the box on its 2 cm rope under the anchor after 1 s, where MuJoCo has it
    assert np.linalg.norm(got - d.qpos[box : box + 3]) < 1e-4, (got, d.qpos[box : box + 3])


class _no_warning:
    """the import reports nothing (every element of the scene modelled)"""

    def __enter__(self):
        import warnings

        self._catch = warnings.catch_warnings(record=True)
        self._seen = self._catch.__enter__()
        warnings.simplefilter("always")

    def __exit__(self, *exc):
        self._catch.__exit__(*exc)
        assert not [str(w.message) for w in self._seen]


def site(body, x, y=0.0, z=0.0):
    return novaphy.TendonPathElement(novaphy.TendonPathKind.Site, body, novaphy.Transform([x, y, z], [0, 0, 0, 1]))


def chain(builder, links):
    parent = -1
    for i in range(links):
        body = builder.add_body(novaphy.RigidBody())
        builder.add_joint_revolute(parent, body, axis=[0, 1, 0])
        parent = body
    return parent


@pytest.mark.parametrize(
    "path, message",
    [
        (lambda b: [site(b, 0.1)], "starts and ends at a site"),
        (
            lambda b: [site(b, 0.1), novaphy.TendonPathElement(novaphy.TendonPathKind.Pulley, -1, size=0), site(-1, 0)],
            "divisor is not > 0",
        ),
        (
            lambda b: [
                site(b, 0.1),
                novaphy.TendonPathElement(novaphy.TendonPathKind.Sphere, b, size=0.1),
                novaphy.TendonPathElement(novaphy.TendonPathKind.Pulley, -1, size=2),
                site(-1, 0),
            ],
            "not between two sites",
        ),
        (
            lambda b: [site(b, 0.1), novaphy.TendonPathElement(novaphy.TendonPathKind.Cylinder, b, size=-1), site(-1, 0)],
            "radius is not > 0",
        ),
        (lambda b: [site(b, 0.1), novaphy.TendonPathElement(novaphy.TendonPathKind.SideSite, b), site(-1, 0)], "side site"),
        (lambda b: [site(-1, 0.1), site(-1, 0)], "world alone"),
        (lambda b: [site(b + 7, 0.1), site(-1, 0)], "out of range"),
    ],
)
def test_a_bad_path_is_refused_naming_the_tendon_and_element(path, message):
    builder = novaphy.ModelBuilder()
    body = chain(builder, 1)
    with pytest.raises(Exception, match=message) as error:
        builder.add_spatial_tendon(path(body), name="cord")
    assert "cord" in str(error.value)


def test_a_tendon_over_three_articulations_is_refused_at_finalize():
    builder = novaphy.ModelBuilder()
    bodies = [chain(builder, 1) for _ in range(3)]
    builder.add_spatial_tendon([site(bodies[0], 0.1), site(bodies[1], 0.1), site(bodies[2], 0.1)], name="cord")
    with pytest.raises(Exception, match="cord.*3 articulations"):
        builder.finalize()
