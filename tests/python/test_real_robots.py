"""Elements of MuJoCo models that change how real robots move, each against today's MuJoCo (PyPI) on an MJCF
written here or a shared Menagerie robot: solimp values outside MuJoCo's ranges (which it clamps where it reads
them), the contact filter's weld rule, gravity compensation (gravcomp), actuators on sites (thrusters), engine
plugin actuators (refused)."""

import warnings

import numpy as np
import pytest

import novaphy
from mujoco_checks import by_route, shared_robot

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh installs it in build/venv)"
)


def both(xml, tmp_path, steps, route="from_mujoco", ctrl=None):
    """today's MuJoCo and NovaPhy (SolverFeatherstone; the model from today's MuJoCo's compile, or the file through
    add_mjcf) step the model `steps` times from its first keyframe (qpos0 without one), its actuators at `ctrl`:
    their final qpos, and NovaPhy's model"""
    path = tmp_path / "model.xml"
    path.write_text(xml)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    if m.nkey:
        mujoco.mj_resetDataKeyframe(m, d, 0)
    if ctrl is not None:
        d.ctrl[:] = ctrl
    mujoco.mj_step(m, d, steps)
    imported, model = by_route(m, path, route)
    state = model.state(keyframe=model.keyframes[0]) if m.nkey else model.state()
    control = model.control()
    for u, a in enumerate(imported.actuator_map if ctrl is not None else []):
        control.actuator_ctrl[a] = ctrl[u]
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.angular_damping = 0  # (MuJoCo has none)
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
    return d.qpos.copy(), imported.to_qpos(np.array(state.joint_q)), model


# a 1 kg box resting on the floor on its own solimp: (2, 1, ...) is Trossen's finger pads' (dmin and dmax clamped to
# 0.9999), (0.2, 0.9, 0.05, 1.5, 0.5) has a midpoint above 1 and a power below 1 (clamped to 0.9999 and 1)
@pytest.mark.parametrize("solimp", ["2 1 0.01 0.5 2", "0.2 0.9 0.05 1.5 0.5", "0.3 0.8 -0.1 0.5 2"])
def test_a_solimp_outside_mujocos_ranges_is_clamped_as_mujoco_clamps_it(tmp_path, solimp):
    xml = f"""<mujoco><worldbody><geom type="plane" size="1 1 0.1"/>
      <body pos="0 0 0.1"><freejoint/><geom type="box" size="0.1 0.1 0.1" mass="1" solimp="{solimp}"/></body>
    </worldbody></mujoco>"""
    expected, got, _ = both(xml, tmp_path, 500)
    # the box sinks to where its impedance holds its weight: the same depth as MuJoCo's
    assert abs(got[2] - expected[2]) < 1e-6, (got[2], expected[2])


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


# two arms of three hinges: one whose links all compensate their weight (gravcomp 1), one whose middle link carries
# half of its own and whose tip none
ARMS = """<mujoco><option timestep="0.002"/><worldbody>{}</worldbody></mujoco>""".format(
    "".join(
        f"""<body name="upper{k}" pos="0 {k / 2} 1" gravcomp="{a}"><joint type="hinge" axis="0 1 0" damping="0.01"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
          <body name="fore{k}" pos="0.3 0 0" gravcomp="{b}"><joint type="hinge" axis="0 1 0"/>
            <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.03"/>
            <body name="hand{k}" pos="0.3 0 0.1" gravcomp="{c}"><joint type="hinge" axis="1 0 0"/>
              <geom type="box" size="0.05 0.03 0.02" pos="0.05 0 0"/></body></body></body>"""
        for k, (a, b, c) in enumerate(((1, 1, 1), (1, 0.5, 0)))
    )
)


@pytest.mark.parametrize("route", ["from_mujoco", "add_mjcf"])
def test_gravity_compensation_holds_the_arms_as_mujoco_does(tmp_path, route):
    expected, got, _ = both(ARMS, tmp_path, 500, route)
    np.testing.assert_allclose(got, expected, atol=1e-12)
    np.testing.assert_allclose(got[:3], 0, atol=1e-12)  # the compensated arm floats where it was put
    assert np.max(np.abs(got[3:])) > 0.1  # the other one sags


def two_boxes(dress):
    """a model of two 2 kg boxes side by side (collisions off), box k dressed by dress(builder, box, k)"""
    b = novaphy.ModelBuilder(gravity=np.array([0.0, 0.0, -9.81]))
    for k in range(2):
        box = b.add_body(novaphy.RigidBody.from_box(2.0, [0.1, 0.2, 0.3]), xform=novaphy.Transform([k, 0, 0]))
        b.add_shape_box(box, [0.1, 0.2, 0.3], collision_group=0, collision_mask=0)
        dress(b, box, k)
    return b.finalize()


def velocities_after_a_second(m, solver, control):
    """body_qd after 100 steps of 10 ms of the solver from the model's initial state"""
    state = m.state()
    pipeline = novaphy.CollisionPipeline(m)
    contacts = pipeline.contacts()
    step = getattr(novaphy.solvers, solver)(m)
    for _ in range(100):
        pipeline.collide(state, contacts)
        step.step(state, state, control, contacts, 0.01)
    return np.array(state.body_qd)


# a free box whose gravcomp is 1 floats, one of 0.5 falls at g / 2, in every solver
@pytest.mark.parametrize("solver", ["SolverFeatherstone", "SolverSemiImplicit", "SolverXPBD"])
def test_gravity_compensation_lifts_a_share_of_the_weight_in_every_solver(solver):
    m = two_boxes(lambda b, box, k: b.set_body_gravcomp(box, (1.0, 0.5)[k]))
    assert list(m.body_gravcomp) == [1.0, 0.5]
    qd = velocities_after_a_second(m, solver, m.control())
    np.testing.assert_allclose(qd[0], 0, atol=1e-12)
    np.testing.assert_allclose(qd[1][2], -0.5 * 9.81 * 1.0, rtol=1e-9)


def test_a_gravcomp_not_finite_or_of_no_body_is_named():
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1), name="link")
    with pytest.raises(ValueError, match="body 0 \\('link'\\): gravcomp is not finite: nan"):
        b.set_body_gravcomp(body, float("nan"))
    with pytest.raises(ValueError, match="set_body_gravcomp: body 3 out of range \\[0, 1\\)"):
        b.set_body_gravcomp(3, 1.0)


# the evaluations see the compensation as the step does: forward dynamics by each method equal MuJoCo's qacc
# (constraints off) at a moving state, and inverse dynamics takes it back to the applied forces (none)
@pytest.mark.parametrize("method", ["batched", "crba", "aba"])
def test_gravity_compensation_in_the_evaluations_as_in_mujoco(tmp_path, method):
    path = tmp_path / "arms.xml"
    path.write_text(ARMS)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    d.qpos[:] = [0.3, -0.7, 1.1, -0.4, 0.9, -1.3]
    d.qvel[:] = [1.0, -2.0, 0.5, 0.7, -0.3, 2.0]
    mujoco.mj_forward(m, d)
    builder = novaphy.ModelBuilder()
    builder.add_mujoco_model(m)
    model = builder.finalize()
    state, control = model.state(), model.control()
    state.joint_q[:] = d.qpos
    state.joint_qd[:] = d.qvel
    qdd = novaphy.eval_forward_dynamics(model, state, control, method=method)
    np.testing.assert_allclose(qdd, d.qacc, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(novaphy.eval_inverse_dynamics(model, state, qdd), 0, atol=1e-10)


# an actuator computed by an engine plugin (shadow_dexee's mujoco.pid) is refused, naming the actuator and the
# plugin instance: importing it as the unit-gain motor its compiled numbers describe would move it wrongly
def test_a_plugin_actuator_is_refused_by_name():
    xml = """<mujoco><extension><plugin plugin="mujoco.pid"><instance name="pid1"><config key="kp" value="40"/>
      </instance></plugin></extension>
      <worldbody><body><joint name="j" type="hinge"/><geom type="sphere" size="0.1"/></body></worldbody>
      <actuator><plugin joint="j" plugin="mujoco.pid" instance="pid1" name="servo"/></actuator></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    with pytest.raises(ValueError, match="actuator 'servo': its force comes from engine plugin instance 0 'pid1'"):
        novaphy.ModelBuilder().add_mujoco_model(m)


# a free body with four tilted thrusters off its centre (a quadrotor's) and an arm whose tip carries one: thrust and
# torque on sites move them as in MuJoCo, on both routes of the import
THRUSTERS = """<mujoco><option timestep="0.005"/><worldbody>
  <body name="drone" pos="0 0 1"><freejoint/><geom type="box" size="0.2 0.2 0.04" mass="1.5"/>
    <geom type="sphere" size="0.05" pos="0.1 0.05 0.05" mass="0.2"/>
    {}
  </body>
  <body name="arm" pos="2 0 1"><joint type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0.4 0 0"
    size="0.03"/><site name="tip" pos="0.4 0 0" quat="0.9 0 0.3 0.1"/></body>
  </worldbody>
  <actuator>{}<motor site="tip" gear="0 0 1 0 0.5 0" ctrlrange="-3 3"/></actuator></mujoco>""".format(
    "".join(
        f'<site name="rotor{k}" pos="{x} {y} 0.05" euler="{0.1 * x} {-0.1 * y} 0"/>'
        for k, (x, y) in enumerate(((0.2, 0.2), (-0.2, 0.2), (-0.2, -0.2), (0.2, -0.2)))
    ),
    "".join(
        f'<motor site="rotor{k}" gear="0 0 1 0 0 {s}" ctrlrange="0 8"/>' for k, s in enumerate((0.02, -0.02, 0.03, -0.01))
    ),
)


@pytest.mark.parametrize("route", ["from_mujoco", "add_mjcf"])
def test_thrusters_on_sites_move_the_bodies_as_in_mujoco(tmp_path, route):
    expected, got, model = both(THRUSTERS, tmp_path, 200, route, ctrl=[4.5, 5.0, 4.0, 5.5, 2.0])
    assert list(model.actuator_body) == [0, 0, 0, 0, 1]
    assert np.max(np.abs(expected[:3] - [0, 0, 1])) > 0.5 and abs(expected[7]) > 0.5  # they moved
    np.testing.assert_allclose(got, expected, atol=1e-9)


# a box lifted by thrust equal to its weight hovers, and one of twice its weight rises at g, in every solver
@pytest.mark.parametrize("solver", ["SolverFeatherstone", "SolverSemiImplicit", "SolverXPBD"])
def test_a_site_actuator_pushes_in_every_solver(solver):
    # a site below the centre, turned a quarter about x: its -y is the body's +z
    site = novaphy.Transform([0.0, 0.0, -0.3], [-np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])
    m = two_boxes(lambda b, box, k: b.add_site_actuator(box, site, gear=[0, -(k + 1) * 2.0 * 9.81, 0, 0, 0, 0]))
    control = m.control()
    control.actuator_ctrl[:] = 1.0
    qd = velocities_after_a_second(m, solver, control)
    np.testing.assert_allclose(qd[0], 0, atol=1e-9)
    np.testing.assert_allclose(qd[1], [0, 0, 9.81, 0, 0, 0], atol=1e-9)


def test_a_bad_site_actuator_is_named():
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    site = novaphy.Transform([0.0, 0.0, 0.1])
    with pytest.raises(ValueError, match="actuator 0 \\('t'\\): a site actuator's body 2 out of range \\[0, 1\\)"):
        b.add_site_actuator(2, site, gear=[0, 0, 1, 0, 0, 0], name="t")
    with pytest.raises(ValueError, match="actuator 0: a site actuator's force cannot depend on the site's velocity"):
        b.add_site_actuator(body, site, gear=[0, 0, 1, 0, 0, 0], bias=[0, 0, -1])
    with pytest.raises(ValueError, match="actuator 0: gear is not finite"):
        b.add_site_actuator(body, site, gear=[0, 0, np.inf, 0, 0, 0])


# a box thrown spinning through a dense, viscous medium with a wind, and a pendulum swinging in it: MuJoCo's
# inertia-box fluid forces (viscous and quadratic drag) slow them as in MuJoCo, on both routes
FLUID = """<mujoco><option timestep="0.002" density="800" viscosity="0.5" wind="1 -0.5 0.2"/><worldbody>
  <body name="box" pos="0 0 1"><freejoint/><geom type="box" size="0.2 0.1 0.05" mass="2"/>
    <geom type="sphere" size="0.04" pos="0.15 0.05 0" mass="0.5"/></body>
  <body name="bob" pos="1 0 1"><joint type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0.3 0 -0.3"
    size="0.04"/></body>
  </worldbody><keyframe><key qvel="2 -1 3 4 -6 2 5"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route", ["from_mujoco", "add_mjcf"])
def test_fluid_forces_slow_the_bodies_as_in_mujoco(tmp_path, route):
    expected, got, model = both(FLUID, tmp_path, 250, route)
    assert (model.fluid_density, model.fluid_viscosity, list(model.wind)) == (800, 0.5, [1, -0.5, 0.2])
    np.testing.assert_allclose(got, expected, atol=1e-9)
    # the medium matters: without it the box would be far from here
    m = mujoco.MjModel.from_xml_string(FLUID)
    m.opt.density = m.opt.viscosity = 0
    dry = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, dry, 0)
    mujoco.mj_step(m, dry, 250)
    assert np.max(np.abs(dry.qpos - expected)) > 0.1


# a box thrown through water slows in every solver as in SolverFeatherstone (the maximal solvers integrate a free
# body much as it does: within 1 % of its velocity after a second), to less than half its speed
@pytest.mark.parametrize("solver", ["SolverSemiImplicit", "SolverXPBD"])
def test_fluid_drag_in_every_solver(solver):
    def thrown():
        b = novaphy.ModelBuilder(gravity=np.array([0.0, 0.0, 0.0]))
        b.set_fluid(1000.0, 1e-3)
        box = b.add_body(novaphy.RigidBody.from_box(2.0, [0.1, 0.2, 0.3]))
        b.add_shape_box(box, [0.1, 0.2, 0.3], collision_group=0, collision_mask=0)
        m = b.finalize()
        state = m.state()
        state.joint_qd[:] = [1.0, -2.0, 0.5, 3.0, 1.0, -1.0]
        novaphy.eval_fk(m, state)  # (the maximal solvers start from body_qd)
        return m, state

    speeds = {}
    for name in ("SolverFeatherstone", solver):
        m, state = thrown()
        pipeline = novaphy.CollisionPipeline(m)
        contacts = pipeline.contacts()
        step = getattr(novaphy.solvers, name)(m)
        step.settings.angular_damping = 0
        for _ in range(100):
            pipeline.collide(state, contacts)
            step.step(state, state, m.control(), contacts, 0.01)
        speeds[name] = np.array(state.body_qd)[0]
    np.testing.assert_allclose(speeds[solver], speeds["SolverFeatherstone"], rtol=0.01, atol=0.01)
    start = np.array(thrown()[1].body_qd)[0]
    assert np.linalg.norm(speeds[solver][:3]) < 0.5 * np.linalg.norm(start[:3])


# MuJoCo's ellipsoid fluid model (a geom's fluidshape="ellipsoid"): a flat card thrown spinning through air with a
# wind (added mass, Kutta and Magnus lift, drag), a pendulum's capsule of its own coefficients in a viscous medium, and
# a body of two geoms of which one is an ellipsoid (the body then feels its ellipsoid alone, no inertia box), on both
# routes
ELLIPSOID_FLUID = """<mujoco><option timestep="0.002" density="1.2" viscosity="0.02" wind="0.5 0 -0.3"/><worldbody>
  <body name="card" pos="0 0 1" euler="0.3 0.2 0"><freejoint/>
    <geom type="ellipsoid" size="0.1 0.07 0.002" mass="0.002" fluidshape="ellipsoid"/></body>
  <body name="bob" pos="1 0 1"><joint type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 -0.3" size="0.04" fluidshape="ellipsoid" fluidcoef="0.3 0.2 1 0.5 2"/>
  </body>
  <body name="pair" pos="0 1 1"><freejoint/><geom type="box" size="0.05 0.1 0.02" mass="0.05"/>
    <geom type="cylinder" size="0.05 0.01" pos="0.1 0 0" mass="0.01" fluidshape="ellipsoid"/></body>
  </worldbody><keyframe><key qvel="3 -1 1 20 -5 40  2  1 0 2 3 -2 10"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route", ["from_mujoco", "add_mjcf"])
def test_the_ellipsoid_fluid_model_moves_the_bodies_as_mujocos(tmp_path, route):
    expected, got, model = both(ELLIPSOID_FLUID, tmp_path, 250, route)
    assert model.fluid_ellipsoid_count == 3
    np.testing.assert_allclose(got, expected, atol=1e-8)
    # the model matters: under the inertia box model (fluidshape off) the card lands elsewhere
    m = mujoco.MjModel.from_xml_string(ELLIPSOID_FLUID.replace(' fluidshape="ellipsoid"', ""))
    box = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, box, 0)
    mujoco.mj_step(m, box, 250)
    assert np.max(np.abs(box.qpos[:7] - expected[:7])) > 0.01


def test_an_ellipsoids_added_mass_and_inertia_are_mujocos():
    # the builder's own coefficients (Tuckerman's integrals by adaptive quadrature) against today's MuJoCo's compile,
    # for a sphere, a flat ellipsoid, a capsule and a long cylinder
    sizes = {"sphere": [0.1, 0.1, 0.1], "ellipsoid": [0.1, 0.07, 0.002], "capsule": [0.04, 0.04, 0.2],
             "cylinder": [0.05, 0.05, 0.4]}
    for name, semi_axes in sizes.items():
        m = mujoco.MjModel.from_xml_string(
            f'<mujoco><worldbody><body><freejoint/><geom type="ellipsoid" size="{" ".join(map(str, semi_axes))}" '
            'fluidshape="ellipsoid"/></body></worldbody></mujoco>'
        )
        b = novaphy.ModelBuilder()
        body = b.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
        b.add_fluid_ellipsoid(body, novaphy.Transform(), semi_axes)
        model = b.finalize()
        np.testing.assert_allclose(model.fluid_ellipsoid_added_mass[0], m.geom_fluid[0, 6:9], rtol=1e-4, err_msg=name)
        np.testing.assert_allclose(
            model.fluid_ellipsoid_added_inertia[0], m.geom_fluid[0, 9:12], rtol=1e-4, atol=1e-12, err_msg=name
        )


def test_a_bad_fluid_ellipsoid_is_named():
    b = novaphy.ModelBuilder()
    body = b.add_body(novaphy.RigidBody())
    with pytest.raises(ValueError, match="fluid ellipsoid 0: body index 3 out of range"):
        b.add_fluid_ellipsoid(3, novaphy.Transform(), [0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="fluid ellipsoid 0: semi-axis must be finite and > 0, got 0"):
        b.add_fluid_ellipsoid(body, novaphy.Transform(), [0.1, 0.0, 0.1])
    with pytest.raises(ValueError, match="fluid ellipsoid 0: added mass must be finite and >= 0, got -1"):
        b.add_fluid_ellipsoid(body, novaphy.Transform(), [0.1, 0.1, 0.1], added_mass=[-1.0, 0.0, 0.0])


def test_a_bad_fluid_is_named():
    b = novaphy.ModelBuilder()
    with pytest.raises(ValueError, match="set_fluid: density must be finite and >= 0, got -1"):
        b.set_fluid(-1.0, 0.0)
    with pytest.raises(ValueError, match="set_fluid: viscosity must be finite and >= 0, got nan"):
        b.set_fluid(1.0, float("nan"))
    with pytest.raises(ValueError, match="set_fluid: wind\\[1\\] is not finite: inf"):
        b.set_fluid(1.0, 0.0, wind=[0.0, np.inf, 0.0])


# MuJoCo's parent filter turned off is reported on both routes: NovaPhy keeps it (a parent and its child never meet)
def test_a_disabled_parent_filter_is_reported(tmp_path):
    path = tmp_path / "unfiltered.xml"
    path.write_text(
        """<mujoco><option><flag filterparent="disable"/></option><worldbody><body><joint type="hinge"/>
        <geom size="0.1"/><body><joint type="hinge"/><geom size="0.1"/></body></body></worldbody></mujoco>"""
    )
    with pytest.warns(UserWarning, match="parent rule is disabled"):
        novaphy.ModelBuilder().add_mujoco_model(mujoco.MjModel.from_xml_path(str(path)))
    with pytest.warns(UserWarning, match="parent rule is disabled"):
        novaphy.ModelBuilder().add_mjcf(str(path))


# a static palm with three fingers, a fixed tendon and a joint equality joining the first and the third (the second
# between them in MuJoCo's order, as Robotiq's `split` joins its drivers), and a free ball: the import adds the joined
# fingers one after the other, its state maps following
SPLIT = """<mujoco><compiler angle="radian"/>
  <default><geom type="capsule" size="0.01" mass="0.1" contype="0" conaffinity="0"/></default>
  <worldbody><body name="palm"><geom type="box" size="0.05 0.05 0.01"/>
      <body name="a" pos="0.03 0 0"><joint name="ja" axis="0 1 0"/><geom fromto="0 0 0 0 0 -0.1"/></body>
      <body name="b" pos="0 0.03 0"><joint name="jb" axis="1 0 0"/><geom fromto="0 0 0 0 0 -0.1"/></body>
      <body name="c" pos="-0.03 0 0"><joint name="jc" axis="0 1 0"/><geom fromto="0 0 0 0 0 -0.1"/></body></body>
    <body name="ball" pos="0 0 -0.3"><freejoint/><geom type="sphere" size="0.02"/></body></worldbody>
  <tendon><fixed name="split" limited="true" range="-0.05 0.05"><joint joint="ja" coef="0.5"/>
    <joint joint="jc" coef="0.5"/></fixed></tendon>
  <equality><joint joint1="ja" joint2="jc" polycoef="0 -1 0 0 0"/></equality>
  <keyframe><key qpos="0.3 0.2 -0.1 0.1 0 -0.3 0.8 0.6 0 0" qvel="0 1 0.5 0.5 0.1 0 1 0 0"/></keyframe></mujoco>"""


@pytest.mark.parametrize("route", ["from_mujoco", "add_mjcf"])
def test_a_tendon_over_fingers_not_one_after_another_joins_them(tmp_path, route):
    path = tmp_path / "split.xml"
    path.write_text(SPLIT)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    imported, model = by_route(m, path, route)
    assert model.articulation_count == 3  # (a and c one articulation; b; the ball)
    state = model.state(keyframe=model.keyframes[0])
    assert np.allclose(imported.to_qpos(np.array(state.joint_q)), d.qpos, rtol=0, atol=1e-15)
    assert np.allclose(imported.to_qvel(d.qpos, np.array(state.joint_qd)), d.qvel, rtol=0, atol=1e-15)
    expected, got, _ = both(SPLIT, tmp_path, 200, route)
    assert np.max(np.abs(got - expected)) < 1e-6, np.max(np.abs(got - expected))


def test_robotiqs_fingers_move_as_mujocos():
    m = mujoco.MjModel.from_xml_path(shared_robot("robotiq_2f85", "scene.xml"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (its scene's spatial tendon modelled: nothing left out)
        builder = novaphy.ModelBuilder()
        imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    d = mujoco.MjData(m)
    state, control = model.state(), model.control()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.angular_damping = 0
    for _ in range(500):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
    mujoco.mj_step(m, d, 500)
    fingers = [m.jnt_qposadr[j] for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    assert len(fingers) == 8
    assert np.max(np.abs(imported.to_qpos(np.array(state.joint_q))[fingers] - d.qpos[fingers])) < 1e-4
