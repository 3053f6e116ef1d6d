"""The core binding: the seed's examples, zero-copy views, dynamics oracles and bad input."""

import warnings

import numpy as np
import pytest

import novaphy

from conftest import HUMANOID


def seed_pendulum_model():
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(y=0.0)
    body_index = builder.add_body(
        novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1], dtype=np.float32)),
    )
    dof = novaphy.JointDofConfig()
    dof.axis = np.array([0, 0, 1], dtype=np.float32)
    joint_index = builder.add_joint_revolute(parent=-1, child=body_index, axis=dof)
    builder.add_articulation([joint_index])
    return builder.finalize()


def test_seed_articulated_bodies_example():
    joint = novaphy.Joint()
    joint.type = novaphy.JointType.Revolute
    joint.axis = np.array([0, 0, 1])
    joint.parent = -1
    body = novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1]))
    joints = [joint]
    bodies = [body]
    q = np.array([0.3])
    transforms = novaphy.forward_kinematics(joints, q)
    assert transforms.shape == (1, 7)
    np.testing.assert_allclose(transforms[0, 5:], [np.sin(0.15), np.cos(0.15)], atol=1e-15)
    H = novaphy.mass_matrix_crba(joints, bodies, q)
    np.testing.assert_allclose(H, [[(0.2**2 + 1.0**2) / 12]], rtol=1e-14)
    gravity = np.array([0.0, -9.81, 0.0])
    tau = novaphy.inverse_dynamics(joints, bodies, q, np.zeros(1), np.array([2.0]), gravity)
    np.testing.assert_allclose(tau, 2.0 * H[0], rtol=1e-14)
    qdd = novaphy.forward_dynamics(joints, bodies, q, np.zeros(1), tau, gravity)
    np.testing.assert_allclose(qdd, [2.0], rtol=1e-14)


def test_seed_builder_example_mass_matrix_is_analytic():
    model = seed_pendulum_model()
    assert (model.body_count, model.joint_count, model.articulation_count, model.shape_count) == (1, 1, 1, 1)
    state = model.state()
    H = novaphy.eval_mass_matrix(model, state)
    # the seed passes float32 half extents: 0.1 arrives as 0.100000001
    np.testing.assert_allclose(H, [[(0.2**2 + 1.0**2) / 12]], rtol=1e-7)


def test_state_views_alias_the_engine_buffers():
    model = seed_pendulum_model()
    state = model.state()
    assert state.joint_q.shape == (1,) and state.body_q.shape == (1, 7) and state.body_qd.shape == (1, 6)
    q_view = state.joint_q
    q_view[0] = np.pi / 2
    state.joint_qd[:] = 2.0
    novaphy.eval_fk(model, state)
    # the write through numpy reached the engine, and the engine's write is seen through numpy
    np.testing.assert_allclose(state.body_q[0, 3:], [0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)], atol=1e-15)
    np.testing.assert_allclose(state.body_qd[0], [0, 0, 0, 0, 0, 2.0], atol=1e-15)
    assert np.shares_memory(q_view, state.joint_q)


def test_model_views_are_read_only():
    model = seed_pendulum_model()
    assert model.joint_type[0] == int(novaphy.JointType.Revolute)
    np.testing.assert_array_equal(model.joint_axis, [[0, 0, 1]])
    with pytest.raises(ValueError):
        model.body_mass[0] = 2.0


def test_views_outlive_their_owner():
    view = seed_pendulum_model().state().body_q
    np.testing.assert_allclose(view[0, 6], 1.0)


def test_humanoid_dynamics_oracles():
    builder = novaphy.ModelBuilder()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # everything in humanoid.xml that matters to dynamics is modelled
        builder.add_mjcf(HUMANOID)
    model = builder.finalize()
    rng = np.random.default_rng(0)
    state = model.state()
    state.joint_q[7:] = rng.uniform(-1, 1, model.joint_coord_count - 7)
    state.joint_qd[:] = rng.uniform(-1, 1, model.joint_dof_count)
    control = model.control()
    control.joint_f[:] = rng.uniform(-1, 1, model.joint_dof_count)

    H = novaphy.eval_mass_matrix(model, state)
    bias = novaphy.eval_bias_forces(model, state)
    columns = np.stack([novaphy.eval_inverse_dynamics(model, state, e) - bias for e in np.eye(model.joint_dof_count)], 1)
    np.testing.assert_allclose(H, columns, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(H) > 0)

    qdd = novaphy.eval_forward_dynamics(model, state, control)
    np.testing.assert_allclose(novaphy.eval_forward_dynamics(model, state, control, method="aba"), qdd, atol=1e-10)
    np.testing.assert_allclose(novaphy.eval_forward_dynamics(model, state, control, method="batched"), qdd, atol=1e-10)
    np.testing.assert_allclose(novaphy.eval_inverse_dynamics(model, state, qdd), control.joint_f, atol=1e-10)
    dynamics = novaphy.ForwardDynamics(model)  # the batched kernels made once, evaluated again and again
    np.testing.assert_allclose(dynamics.evaluate(state, control), qdd, atol=1e-10)
    state.joint_qd[0] += 1.0
    np.testing.assert_allclose(
        dynamics.evaluate(state, control), novaphy.eval_forward_dynamics(model, state, control), atol=1e-10
    )


def test_humanoid_motors_drive_through_their_gear():
    builder = novaphy.ModelBuilder()
    builder.add_mjcf(HUMANOID)
    model = builder.finalize()
    assert model.actuator_count == 21 and model.actuator_name[5] == "right_hip_y"
    control = model.control()
    assert control.actuator_ctrl.shape == (21,)
    control.actuator_ctrl[5] = 3.0  # beyond ctrlrange [-1, 1]
    tau = novaphy.eval_control_force(model, control)
    dof = model.joint_qd_start[model.actuator_joint[5]]
    assert tau[dof] == 120.0 and np.count_nonzero(tau) == 1


def test_bad_builder_input_raises_value_error_naming_the_item():
    builder = novaphy.ModelBuilder()
    with pytest.raises(ValueError, match=r"body 0 \('arm'\): mass must be > 0, got 0"):
        builder.add_body(novaphy.RigidBody(mass=0.0), name="arm")
    with pytest.raises(ValueError, match="inertia violates the triangle inequality"):
        builder.add_body(novaphy.RigidBody(mass=1.0, inertia=np.diag([1.0, 1.0, 3.0])))
    b = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    with pytest.raises(ValueError, match=r"parent body index 4 out of range \[-1, 1\)"):
        builder.add_joint_revolute(4, b)
    with pytest.raises(ValueError, match="axis has zero length"):
        builder.add_joint_revolute(-1, b, axis=[0, 0, 0])
    with pytest.raises(ValueError, match=r"parent_xform\[1\] is not finite: nan"):
        builder.add_joint_ball(-1, b, parent_xform=novaphy.Transform([0, np.nan, 0]))
    with pytest.raises(TypeError, match="axis must be a JointDofConfig or a sequence of 3 numbers"):
        builder.add_joint_revolute(-1, b, axis="z")
    builder.add_joint_revolute(-1, b)
    with pytest.raises(ValueError, match="body 0 is already the child of joint 0"):
        builder.add_joint_revolute(-1, b)


def test_bad_dynamics_input():
    joint = novaphy.Joint()
    body = novaphy.RigidBody.from_box(1.0, [0.1, 0.5, 0.1])
    with pytest.raises(ValueError, match="q has 2 entries, the joints need 1"):
        novaphy.mass_matrix_crba([joint], [body], np.zeros(2))
    with pytest.raises(ValueError, match=r"qd\[0\] is not finite: nan"):
        novaphy.forward_dynamics([joint], [body], np.zeros(1), np.array([np.nan]), np.zeros(1), np.zeros(3))
    with pytest.raises(TypeError):
        novaphy.forward_kinematics([joint], "not an array")
    with pytest.raises(ValueError, match="method must be 'crba', 'aba' or 'batched'"):
        model = seed_pendulum_model()
        novaphy.eval_forward_dynamics(model, model.state(), model.control(), method="rk4")


def test_state_from_another_model_is_rejected():
    model = seed_pendulum_model()
    other = novaphy.ModelBuilder()
    other.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    with pytest.raises(ValueError, match="state or control from another model"):
        novaphy.eval_fk(model, other.finalize().state())


def test_unmodelled_mjcf_content_warns_by_name(tmp_path):
    path = tmp_path / "tendon.xml"
    path.write_text(
        '<mujoco><worldbody><body name="a"><joint name="ja" type="hinge"/><geom size="0.1"/><site name="s"/>'
        '<site name="t" pos="0 0 1"/></body></worldbody>'
        '<tendon><spatial name="coupling"><site site="s"/><site site="t"/></spatial></tendon>'
        '<equality><tendon name="lock" tendon1="coupling"/></equality>'
        "</mujoco>"
    )
    builder = novaphy.ModelBuilder()
    with pytest.warns(UserWarning, match="novaphy: equality constraint 'lock'"):
        reported = builder.add_mjcf(str(path))
    assert len(reported) == 1 and reported[0].endswith("not modelled (affects motion)")


def test_mjcf_errors_pass_mujocos_message_on(tmp_path):
    builder = novaphy.ModelBuilder()
    with pytest.raises(ValueError, match="file does not exist"):
        builder.add_mjcf(str(tmp_path / "missing.xml"))
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body></worldbody></mujoco>")
    with pytest.raises(ValueError, match="XML parse error"):
        builder.add_mjcf(str(broken))


def test_imported_quadruped_falls_freely_at_rest(scene):
    builder = novaphy.ModelBuilder()
    builder.add_mjcf(scene("quadruped.xml"))
    model = builder.finalize()
    np.testing.assert_allclose(model.gravity, [0, 0, -9.81])
    qdd = novaphy.eval_forward_dynamics(model, model.state(), model.control())
    # every link falls together: the free joint accelerates at g, the hinges stay put
    np.testing.assert_allclose(qdd[:6], [0, 0, 0, 0, 0, -9.81], atol=1e-12)
    np.testing.assert_allclose(qdd[6:], 0, atol=1e-12)


def test_new_shapes_and_soft_contacts_from_python():
    # a cylinder, an ellipsoid and a mesh hull resting on the ground; the mesh's contacts soft (both shapes carry a
    # solref: a pair of equal priority with one rigid shape is rigid), a solimp soft at the surface sinking it
    b = novaphy.ModelBuilder()
    b.add_ground_plane(solref=(0.02, 1.0), solimp=(0.5, 0.95, 0.01, 0.5, 2))
    can = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.05, 0.1]), xform=novaphy.Transform([0, 0.05, 0]))
    b.add_shape_cylinder(can, 0.1, 0.05)
    egg = b.add_body(novaphy.RigidBody.from_sphere(1.0, 0.08), xform=novaphy.Transform([1, 0.08, 0]))
    b.add_shape_ellipsoid(egg, [0.15, 0.08, 0.12])
    cube = np.array([[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)])
    brick = b.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]), xform=novaphy.Transform([2, 0.1, 0]))
    soft = {"solref": (0.02, 1.0), "solimp": (0.5, 0.95, 0.01, 0.5, 2)}
    b.add_shape_mesh(brick, b.add_mesh(cube, name="cube"), name="brick", **soft)
    m = b.finalize()
    kinds = [novaphy.ShapeType.Cylinder, novaphy.ShapeType.Ellipsoid, novaphy.ShapeType.Mesh]
    assert [novaphy.ShapeType(t) for t in m.shape_type[1:]] == kinds
    assert m.mesh_vertex.shape == (8, 3) and m.mesh_face_plane.shape == (6, 4)
    assert m.shape_solref[3][0] == 0.02 and m.shape_name[3] == "brick"
    state, control = m.state(), m.control()
    pipeline = novaphy.CollisionPipeline(m)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(m)
    for _ in range(240):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 1.0 / 120)
    heights = state.body_q[:, 1]
    assert abs(heights[0] - 0.05) < 1e-3 and abs(heights[1] - 0.08) < 1e-3
    assert 0.09 < heights[2] < 0.1 - solver.settings.linear_slop  # soft: deeper than a rigid contact's slop
    with pytest.raises(ValueError, match="mesh 1 \\('flat'\\): the points span no volume"):
        b.add_mesh(cube * [1, 0, 1], name="flat")
    with pytest.raises(ValueError, match="solimp must be five finite numbers"):
        b.add_shape_sphere(can, 0.1, solimp=(0.9, float("nan"), 0.001, 0.5, 2))
