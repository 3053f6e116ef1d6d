"""SolverSemiImplicit and SolverXPBD through the binding: the maximal-coordinate joints' adders, joint_support,
Featherstone's refusal, a step on a float32 state, one step at a time per solver, and bad input named."""

import threading

import numpy as np
import pytest

import novaphy

SOLVERS = [novaphy.solvers.SolverSemiImplicit, novaphy.solvers.SolverXPBD]


def rope(segments=5, precision=None):
    """A rope of capsule segments joined by Cable joints, hanging from the world by a Distance joint."""
    builder = novaphy.ModelBuilder()
    if precision is not None:
        builder.precision = precision
    builder.add_ground_plane(y=-2.0)
    parent = -1
    for i in range(segments):
        body = builder.add_body(novaphy.RigidBody.from_capsule(0.1, 0.02, 0.05), xform=novaphy.Transform([0, -0.1 * i - 0.05, 0]))
        builder.add_shape_capsule(body, 0.02, 0.05)
        if parent < 0:
            builder.add_joint_distance(-1, body, child_xform=novaphy.Transform([0, 0.05, 0]), max_distance=0.01)
        else:
            builder.add_joint_cable(parent, body, parent_xform=novaphy.Transform([0, -0.05, 0]),
                                    child_xform=novaphy.Transform([0, 0.05, 0]), stretch_compliance=1e-6,
                                    bend_compliance=1.0)
        parent = body
    return builder.finalize()


@pytest.mark.parametrize("solver_type", SOLVERS)
def test_a_rope_swings_and_its_joints_follow_its_bodies(solver_type):
    model = rope()
    solver = solver_type(model)
    state, control = model.state(), model.control()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    state.body_qd[-1, 0] = 1.0  # the last segment pushed sideways
    for _ in range(120):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 1.0 / 120)
    assert np.all(np.isfinite(state.body_q))
    # the segments stay joined: each one's top at its parent's bottom
    q = np.array(state.body_q)
    for i in range(1, len(q)):
        top = q[i, :3] + rotate(q[i, 3:], [0, 0.05, 0])
        bottom = q[i - 1, :3] + rotate(q[i - 1, 3:], [0, -0.05, 0])
        assert np.linalg.norm(top - bottom) < 2e-3
    # joint_q is each Cable's pose in its parent's frame, from the bodies
    assert abs(np.linalg.norm(np.array(state.joint_q)[10:14]) - 1) < 1e-9
    assert not solver.diverged.any()


def rotate(q, v):
    """v turned by the quaternion q = [x, y, z, w]."""
    u, w = np.array(q[:3]), q[3]
    v = np.array(v, dtype=float)
    return v + 2 * w * np.cross(u, v) + 2 * np.cross(u, np.cross(u, v))


@pytest.mark.parametrize("solver_type", SOLVERS)
def test_joint_support_and_featherstones_refusal(solver_type):
    model = rope(2)
    support = solver_type(model).joint_support()
    assert all(support.joints.values())
    assert "Cable: yes" in str(support)
    fs_support = novaphy.solvers.SolverFeatherstone(rope_free_model()).joint_support()
    assert not fs_support["D6"] and fs_support["Revolute"]
    with pytest.raises(ValueError, match=r"SolverFeatherstone does not enforce joint 0 \(Distance\)"):
        novaphy.solvers.SolverFeatherstone(model)


def rope_free_model():
    builder = novaphy.ModelBuilder()
    builder.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.1, 0.1])))
    return builder.finalize()


@pytest.mark.parametrize("solver_type", SOLVERS)
def test_a_float32_state_steps_in_place(solver_type):
    model = rope(3, novaphy.Precision.Float32)
    solver = solver_type(model)
    state, control = model.state(), model.control()
    assert state.body_q.dtype == np.float32
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    state.body_qd[-1, 0] = 1.0
    before = np.array(state.body_q)
    for _ in range(10):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 1.0 / 120)
    assert not np.array_equal(before, state.body_q) and np.all(np.isfinite(state.body_q))


@pytest.mark.parametrize("solver_type", SOLVERS)
def test_threads_sharing_a_solver_are_refused_not_raced(solver_type):
    builder = novaphy.ModelBuilder()
    builder.replicate(rope_builder(), 64)
    model = builder.finalize()
    solver = solver_type(model)
    state, control = model.state(), model.control()
    contacts = novaphy.CollisionPipeline(model).contacts()
    errors, done = [], []

    def loop():
        for _ in range(50):
            try:
                solver.step(state, state, control, contacts, 1.0 / 240)
                done.append(1)
            except ValueError as e:
                errors.append(str(e))

    threads = [threading.Thread(target=loop) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(done) + len(errors) == 100
    assert all("step called while another call of the same object runs on another thread" in e for e in errors)


def rope_builder():
    builder = novaphy.ModelBuilder()
    parent = -1
    for i in range(3):
        body = builder.add_body(novaphy.RigidBody.from_capsule(0.1, 0.02, 0.05), xform=novaphy.Transform([0, -0.1 * i - 0.05, 0]))
        builder.add_joint_cable(parent, body, parent_xform=novaphy.Transform([0, -0.05 if parent >= 0 else 0, 0]),
                                child_xform=novaphy.Transform([0, 0.05, 0]))
        parent = body
    return builder


def test_bad_input_is_named():
    builder = novaphy.ModelBuilder()
    a = builder.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.1, 0.1])))
    with pytest.raises(ValueError, match="min_distance must be finite and >= 0"):
        builder.add_joint_distance(-1, a, min_distance=-1.0)
    with pytest.raises(ValueError, match=r"angular_axes\[0\] has zero length"):
        builder.add_joint_d6(-1, a, angular_axes=[[0, 0, 0]])
    with pytest.raises(ValueError, match=r"\(Cable\): bend_compliance must be finite and >= 0, got -1"):
        builder.add_joint_cable(-1, a, bend_compliance=-1.0)
    d6 = builder.add_joint_d6(-1, a, linear_axes=[[0, 1, 0]], angular_axes=[novaphy.JointDofConfig()])
    model = builder.finalize()
    assert model.joint_type[d6] == int(novaphy.JointType.D6)
    with pytest.raises(ValueError, match="settings.iterations must be >= 1, got 0"):
        novaphy.solvers.SolverXPBD(model, iterations=0)
    with pytest.raises(ValueError, match="settings.substeps must be >= 1, got -2"):
        novaphy.solvers.SolverXPBD(model, substeps=-2)
    with pytest.raises(ValueError, match="settings.joint_angular_compliance must be >= 0"):
        novaphy.solvers.SolverXPBD(model, joint_angular_compliance=-1.0)
    solver = novaphy.solvers.SolverSemiImplicit(model)
    solver.settings.erp = 2.0
    state, control = model.state(), model.control()
    contacts = novaphy.CollisionPipeline(model).contacts()
    with pytest.raises(ValueError, match=r"settings.erp must be in \[0, 1\], got 2"):
        solver.step(state, state, control, contacts, 0.01)


@pytest.mark.parametrize("solver_type", SOLVERS)
def test_what_a_solver_does_not_model_is_warned_by_name(solver_type):
    builder = novaphy.ModelBuilder()
    body = builder.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.1, 0.1])))
    builder.add_joint_revolute(-1, body, axis=[0, 0, 1], armature=0.01, frictionloss=0.5, name="knee")
    model = builder.finalize()
    with pytest.warns(UserWarning, match="joint 0 'knee': armature"):
        solver = solver_type(model)
    assert solver.ignored == ["joint 0 'knee': armature 0.010000", "joint 0 'knee': frictionloss 0.500000"]
