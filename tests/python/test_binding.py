"""Every bound class and function, the views' shapes and aliasing, and dtype/shape errors."""

import threading

import numpy as np
import pytest

import novaphy



def every_joint_model():
    builder = novaphy.ModelBuilder(gravity=[0.0, 0.0, -9.81])
    bodies = [builder.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]), name=f"b{k}") for k in range(6)]
    free = builder.add_joint_free(-1, bodies[0], name="root")
    ball = builder.add_joint_ball(bodies[0], bodies[1], parent_xform=novaphy.Transform([0, 0, -0.2]))
    hinge = builder.add_joint_revolute(bodies[1], bodies[2], axis=[0, 1, 0], limit_lower=-1.0, limit_upper=1.0)
    slide = builder.add_joint_slide(bodies[2], bodies[3], axis=[0, 0, 1])
    prismatic = builder.add_joint_prismatic(bodies[3], bodies[4], axis=[1, 0, 0], armature=0.1, damping=0.2)
    fixed = builder.add_joint_fixed(bodies[4], bodies[5], child_xform=novaphy.Transform([0, 0, 0.1]))
    builder.add_articulation([free, ball, hinge, slide, prismatic, fixed])
    motor = builder.add_motor(hinge, gear=10.0, ctrl_lower=-1.0, ctrl_upper=1.0, name="m")
    builder.add_plane([0, 0, 1], -1.0)
    builder.add_shape_capsule(bodies[5], 0.05, 0.1)
    return builder, builder.finalize(), motor


def test_every_joint_type_and_the_model_views():
    builder, model, motor = every_joint_model()
    assert (builder.body_count, builder.joint_count, builder.shape_count, builder.actuator_count) == (6, 6, 2, 1)
    assert list(model.joint_type) == [int(t) for t in (novaphy.JointType.Free, novaphy.JointType.Ball,
                                                       novaphy.JointType.Revolute, novaphy.JointType.Slide,
                                                       novaphy.JointType.Prismatic, novaphy.JointType.Fixed)]
    assert model.joint_coord_count == 7 + 4 + 1 + 1 + 1 and model.joint_dof_count == 6 + 3 + 1 + 1 + 1
    assert model.joint_name[0] == "root" and model.body_name[3] == "b3" and model.actuator_name[motor] == "m"
    # every field view has the field table's shape
    assert model.joint_X_p.shape == (6, 7) and model.joint_axis.shape == (6, 3)
    assert model.joint_q_start.shape == (7,) and model.articulation_start.shape == (2,)
    assert model.body_inertia.shape == (6, 9) and model.shape_transform.shape == (2, 7)
    assert model.joint_armature.shape == (12,) and model.joint_armature[-1] == 0.1
    assert model.shape_type[0] == int(novaphy.ShapeType.Plane) and model.shape_type[1] == int(novaphy.ShapeType.Capsule)
    assert model.joint_q_start.dtype == np.int32 and model.body_mass.dtype == np.float64
    np.testing.assert_allclose(model.gravity, [0, 0, -9.81])
    np.testing.assert_array_equal(model.joint_limit_lower[[9]], [-1.0])


def test_state_views_write_through_and_the_next_step_sees_them():
    _, model, _ = every_joint_model()
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts, state, control = pipeline.contacts(), model.state(), model.control()
    state.joint_qd[3:6] = [1.0, 0.0, 0.0]  # the free joint's linear velocity, written through numpy
    solver.step(state, state, control, contacts, 0.01)
    assert state.joint_q[0] == pytest.approx(0.01, rel=1e-9)  # the step used the written velocity
    control.actuator_ctrl[0] = 5.0
    tau = novaphy.eval_control_force(model, control)
    assert tau[9] == 10.0  # clamped to ctrl 1, gear 10


def test_views_reject_wrong_shapes_and_read_only_writes():
    _, model, _ = every_joint_model()
    state = model.state()
    with pytest.raises(ValueError):
        state.body_q[:] = np.zeros((2, 7))
    with pytest.raises(ValueError):
        model.joint_axis[0, 0] = 1.0
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    pipeline.collide(state, contacts)
    with pytest.raises(ValueError):
        contacts.contact_depth[:] = 0.0


def test_arguments_of_the_wrong_dtype_or_shape():
    joint = novaphy.Joint()
    body = novaphy.RigidBody.from_box(1.0, [0.1, 0.5, 0.1])
    with pytest.raises(TypeError):
        novaphy.mass_matrix_crba([joint], [body], np.zeros((1, 1, 1)))
    with pytest.raises(TypeError):
        novaphy.mass_matrix_crba([joint], [body], ["a"])
    with pytest.raises(TypeError):
        novaphy.RigidBody.from_box(1.0, [0.1, 0.5])
    with pytest.raises(TypeError):
        novaphy.mass_matrix_crba([body], [body], np.zeros(1))
    # integer and float32 arrays convert
    assert novaphy.mass_matrix_crba([joint], [body], np.zeros(1, dtype=np.int64)).shape == (1, 1)
    assert novaphy.mass_matrix_crba([joint], [body], np.zeros(1, dtype=np.float32)).shape == (1, 1)


def test_error_type_is_a_value_error():
    assert issubclass(novaphy.Error, ValueError)
    with pytest.raises(novaphy.Error, match="mass must be > 0"):
        novaphy.ModelBuilder().add_body(novaphy.RigidBody(mass=-1.0))


def test_transform_algebra():
    a = novaphy.Transform([1.0, 0.0, 0.0], [0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)])
    b = a * a.inverse()
    np.testing.assert_allclose(b.position, 0, atol=1e-15)
    np.testing.assert_allclose(np.abs(b.rotation), [0, 0, 0, 1], atol=1e-15)
    c = a * novaphy.Transform([1.0, 0.0, 0.0])
    np.testing.assert_allclose(c.position, [1, 1, 0], atol=1e-15)
    assert "Transform(position=" in repr(a)
    d = novaphy.JointDofConfig()
    d.axis, d.limit_lower, d.limit_upper, d.armature, d.damping, d.stiffness, d.q_ref = [0, 1, 0], -1, 1, 0.1, 0.2, 3, 0.5
    d.target_ke, d.target_kd = 10.0, 1.0
    assert (d.limit_lower, d.stiffness, d.target_ke) == (-1, 3, 10.0)


def test_urdf_import(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(
        '<robot name="arm"><link name="base"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1"'
        ' ixy="0" ixz="0" iyz="0"/></inertial></link><link name="upper"><inertial><mass value="1"/>'
        '<inertia ixx="0.02" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    builder = novaphy.ModelBuilder()
    assert builder.add_urdf(str(path)) == []
    assert builder.finalize().joint_dof_count == 1


def test_long_calls_release_the_gil():
    # a 2000-link chain: one mass_matrix_crba call runs long enough to count Python ticks during it
    joints, bodies = [], []
    for i in range(2000):
        joint = novaphy.Joint()
        joint.axis = [0.0, 0.0, 1.0]
        joint.parent = i - 1
        joint.parent_to_joint = novaphy.Transform([0.1, 0.0, 0.0])
        joints.append(joint)
        bodies.append(novaphy.RigidBody.from_box(1.0, [0.05, 0.01, 0.01]))
    q = np.zeros(2000)
    entered, done = threading.Event(), threading.Event()

    def compute():
        entered.set()
        novaphy.mass_matrix_crba(joints, bodies, q)
        done.set()

    thread = threading.Thread(target=compute)
    thread.start()
    entered.wait()
    ticks = 0
    while not done.is_set():
        ticks += 1  # runs only while the other thread is inside the engine without the GIL
        done.wait(0.001)
    thread.join()
    assert ticks > 5


def test_state_checkpoints():
    _, model, _ = every_joint_model()
    state = model.state()
    state.joint_qd[:] = np.linspace(-1, 1, model.joint_dof_count)
    snapshot = state.to_numpy()
    assert set(snapshot) == {"joint_q", "joint_qd", "body_q", "body_qd", "body_f", "world_reset", "sensor_data"}
    assert snapshot["body_q"].shape == (6, 7) and not np.shares_memory(snapshot["joint_qd"], state.joint_qd)
    assert snapshot["world_reset"].dtype == np.uint8 and snapshot["world_reset"].tolist() == [0]
    copy = state.copy()
    state.joint_qd[:] = 0.0
    np.testing.assert_array_equal(copy.joint_qd, snapshot["joint_qd"])  # the copy is independent
    state.assign(copy)
    np.testing.assert_array_equal(state.joint_qd, snapshot["joint_qd"])
    state.joint_qd[:] = 0.0
    state.from_numpy({"joint_qd": snapshot["joint_qd"][::-1][::-1], "body_f": np.zeros((6, 6), dtype=np.int64)})
    np.testing.assert_array_equal(state.joint_qd, snapshot["joint_qd"])
    state.from_numpy({"world_reset": np.ones(1, dtype=np.int64)})
    assert state.world_reset.tolist() == [1]
    # nothing is written when any array is wrong
    with pytest.raises(ValueError, match=r"from_numpy: field 'body_q' has shape \(7, 6\), expected \(6, 7\)"):
        state.from_numpy({"joint_qd": np.zeros(12), "body_q": np.zeros((7, 6))})
    np.testing.assert_array_equal(state.joint_qd, snapshot["joint_qd"])
    with pytest.raises(ValueError, match="from_numpy: unknown field 'joint_qdd'"):
        state.from_numpy({"joint_qdd": np.zeros(12)})
    with pytest.raises(TypeError, match="from_numpy: field 'joint_q' must be a numeric array"):
        state.from_numpy({"joint_q": np.array(["a"] * 14)})
    other = novaphy.ModelBuilder()
    other.add_body(novaphy.RigidBody())
    with pytest.raises(ValueError, match="assign: the other state belongs to a model with"):
        state.assign(other.finalize().state())
    control = model.control()
    control.joint_f[:] = 1.0
    restored = model.control()
    restored.from_numpy(control.to_numpy())
    np.testing.assert_array_equal(restored.joint_f, 1.0)
    restored.assign(model.control())
    np.testing.assert_array_equal(restored.joint_f, 0.0)


def test_replicate_and_add_builder():
    robot = novaphy.ModelBuilder()
    link = robot.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
    robot.add_joint_revolute(-1, link, axis=[0, 0, 1], child_xform=novaphy.Transform([-0.25, 0, 0]))
    robot.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1), xform=novaphy.Transform([0, 1, 0]))
    batch = novaphy.ModelBuilder()
    batch.replicate(robot, 3, spacing=[2.0, 0.0, 0.0])
    batch.add_builder(robot, xform=novaphy.Transform([0, 0, 5]), world=7)
    assert batch.world_count == 8
    model = batch.finalize()
    np.testing.assert_array_equal(model.body_world, [0, 0, 1, 1, 2, 2, 7, 7])
    state = model.state()
    np.testing.assert_allclose(state.body_q[[1, 3, 5, 7], :3], [[0, 1, 0], [2, 1, 0], [4, 1, 0], [0, 1, 5]])


def test_world_views():
    robot = novaphy.ModelBuilder()
    a = robot.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
    b = robot.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
    robot.add_joint_ball(-1, a)
    robot.add_joint_revolute(a, b, axis=[0, 0, 1])
    batch = novaphy.ModelBuilder()
    batch.replicate(robot, 3)
    model = batch.finalize()
    state = model.state()
    q = novaphy.world_view(model, state.joint_q)
    assert q.shape == (3, 5) and novaphy.world_view(model, state.body_q).shape == (3, 2, 7)
    assert novaphy.world_view(model, state.joint_qd).shape == (3, 4)
    q[2, 4] = 0.7  # world 2's hinge, written through the view
    assert state.joint_q[14] == 0.7
    uneven = novaphy.ModelBuilder()
    uneven.replicate(robot, 2)
    uneven.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))  # one more body in world 0
    other = uneven.finalize()
    with pytest.raises(ValueError, match="the worlds of this model differ in layout"):
        novaphy.world_view(other, other.state().joint_q)


def test_shards_of_worlds():
    ranges = [novaphy.shard_range(7, r, 3) for r in range(3)]
    assert [(r.begin, r.end, r.count) for r in ranges] == [(0, 3, 3), (3, 5, 2), (5, 7, 2)]
    with pytest.raises(ValueError, match=r"shard_range: rank must be in \[0, 3\), got 3"):
        novaphy.shard_range(7, 3, 3)

    def pendulum(builder, w):  # edits the builder it is given, which the engine keeps
        link = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
        builder.add_joint_revolute(-1, link, parent_xform=novaphy.Transform([float(w), 0, 0]))

    shared = novaphy.ModelBuilder()
    shared.add_ground_plane(-1.0)
    part = novaphy.build_worlds(shared, pendulum, ranges[1])
    whole = novaphy.build_worlds(shared, pendulum, novaphy.shard_range(7, 0, 1))
    assert part.world_count == 2 and part.shape_count == 1 and whole.world_count == 7
    np.testing.assert_array_equal(part.joint_X_p, whole.joint_X_p[3:5])
    layout = novaphy.world_layout(whole)
    assert (layout.world_count, layout.body_count, layout.joint_dof_count, layout.articulation_count) == (7, 1, 1, 1)
    assert (layout.joint_coord_count, layout.actuator_count) == (1, 0)

    def uneven(builder, w):
        for _ in range(w + 1):
            builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))

    with pytest.raises(ValueError, match="world_layout: world 1 has 2 bodies, world 0 has 1"):
        novaphy.world_layout(novaphy.build_worlds(novaphy.ModelBuilder(), uneven, ranges[0]))
    with_bodies = novaphy.ModelBuilder()
    with_bodies.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    with pytest.raises(ValueError, match="the shared builder holds 1 bodies; it may hold only static shapes"):
        novaphy.build_worlds(with_bodies, pendulum, ranges[0])


def test_stage_seconds_and_implicit_coriolis_settings():
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane()
    box = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.2, 0.2, 0.2]), xform=novaphy.Transform([0, 0.19, 0]))
    builder.add_shape_box(box, [0.2, 0.2, 0.2])
    model = builder.finalize()
    state, control = model.state(), model.control()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.profile_stages = True
    solver.settings.coriolis_implicitness = 0.5
    solver.settings.aba_min_dofs = 0
    for _ in range(5):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 0.01)
    t = solver.stage_seconds
    assert t["steps"] == 5 and all(t[k] > 0 for k in ("dynamics", "contact_rows", "solve", "integrate"))
    solver.reset_stage_seconds()
    assert solver.stage_seconds["steps"] == 0
    solver.settings.count_serial_time = True
    for _ in range(3):
        solver.step(state, state, control, contacts, 0.01)
    s = solver.serial_seconds
    assert s["steps"] == 3 and 0 < s["parallel"] < s["step"] and 0 < s["share"] < 1
    solver.reset_serial_seconds()
    assert solver.serial_seconds["steps"] == 0
    timed = novaphy.CollisionPipeline(model, num_threads=1, count_serial_time=True)
    assert pipeline.serial_seconds["steps"] == 0  # off unless asked for
    for _ in range(3):
        timed.collide(state, contacts)
    s = timed.serial_seconds
    assert s["steps"] == 3 and 0 < s["parallel"] < s["step"] and 0 < s["share"] < 1
    timed.reset_serial_seconds()
    assert timed.serial_seconds["steps"] == 0
    solver.settings.coriolis_implicitness = 1.5
    with pytest.raises(ValueError, match="coriolis_implicitness"):
        solver.step(state, state, control, contacts, 0.01)


def test_eval_energy():
    builder = novaphy.ModelBuilder(gravity=[0.0, -9.81, 0.0])
    ball = builder.add_body(novaphy.RigidBody.from_sphere(2.0, 0.1), xform=novaphy.Transform([0, 3.0, 0]))
    model = builder.finalize()
    state = model.state()
    assert novaphy.eval_energy(model, state) == pytest.approx(2.0 * 9.81 * 3.0, rel=1e-12)
    state.joint_qd[3:6] = [1.0, 0.0, 0.0]  # the free joint's linear velocity (after the angular)
    novaphy.eval_fk(model, state)
    assert novaphy.eval_energy(model, state) == pytest.approx(2.0 * 9.81 * 3.0 + 0.5 * 2.0, rel=1e-12)
    assert ball == 0


def test_keyframes_give_every_world_its_state_and_commands():
    robot = novaphy.ModelBuilder(gravity=[0.0, 0.0, 0.0])
    body = robot.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    hinge = robot.add_joint_revolute(parent=-1, child=body, axis=[0.0, 0.0, 1.0])
    robot.add_position(hinge, kp=10.0)
    robot.add_keyframe("home", [0.3], [0.5], [0.7])
    worlds = novaphy.ModelBuilder(gravity=[0.0, 0.0, 0.0])
    worlds.replicate(robot, 4)
    model = worlds.finalize()
    assert model.keyframes == ["home"] and model.keyframe_q.shape == (1, 4)
    state, control = model.state(keyframe="home"), model.control(keyframe="home")
    assert list(state.joint_q) == [0.3] * 4 and list(state.joint_qd) == [0.5] * 4
    assert list(control.actuator_ctrl) == [0.7] * 4
    assert list(model.state().joint_q) == [0.0] * 4
    with pytest.raises(ValueError, match="no keyframe 'stand': the model has 'home'"):
        model.state(keyframe="stand")


def test_an_imported_model_filters_by_mujocos_rule_and_keeps_excluded_shapes_apart():
    builder = novaphy.ModelBuilder()
    assert builder.collision_filter == novaphy.CollisionFilter.GroupAndMask
    a = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    b = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1), xform=novaphy.Transform([0.15, 0, 0]))
    builder.add_shape_sphere(a, 0.1, collision_group=1, collision_mask=0)
    builder.add_shape_sphere(b, 0.1, collision_group=0, collision_mask=1)
    for rule, found in ((novaphy.CollisionFilter.GroupAndMask, 0), (novaphy.CollisionFilter.Mujoco, 1)):
        builder.collision_filter = rule
        model = builder.finalize()
        assert model.collision_filter == rule
        pipeline = novaphy.CollisionPipeline(model)
        contacts = pipeline.contacts()
        pipeline.collide(model.state(), contacts)
        assert contacts.contact_count == found
    builder.exclude_bodies(a, b)
    model = builder.finalize()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    pipeline.collide(model.state(), contacts)
    assert contacts.contact_count == 0 and list(model.exclude_shape[0]) == [0, 1]
