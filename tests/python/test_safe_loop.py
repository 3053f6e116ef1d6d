"""The user's loop made safe: what a new user's bad or extreme inputs get — a clear error naming the culprit, or the
right answer — never a crash or a silently wrong result."""

import gc

import numpy as np
import pytest

import novaphy

QUADRUPED = "bench/scenes/quadruped.xml"  # +Z up, <option timestep="0.005">


def pendulum(builder, world=0):
    link = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    builder.add_joint_revolute(-1, link, axis=[0, 1, 0], parent_xform=novaphy.Transform([float(world), 0, 0]),
                               child_xform=novaphy.Transform([0, 0, 0.5]))


def mjcf_robot():
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(QUADRUPED)
    return robot


@pytest.mark.parametrize("how", ["replicate", "add_builder", "build_worlds"])
def test_a_scene_takes_its_worlds_gravity_and_timestep_where_the_user_gave_none(how):
    robot = mjcf_robot()
    assert list(robot.gravity) == [0, 0, -9.81] and robot.gravity_given and robot.timestep == 0.005
    if how == "build_worlds":
        model = novaphy.build_worlds(novaphy.ModelBuilder(), lambda b, w: b.add_mjcf(QUADRUPED),
                                     novaphy.shard_range(2, 0, 1))
    else:
        scene = novaphy.ModelBuilder()
        if how == "replicate":
            scene.replicate(robot, 2)
        else:
            scene.add_builder(robot)
            scene.add_builder(robot)
        model = scene.finalize()
    assert list(model.gravity) == [0, 0, -9.81] and model.timestep == 0.005
    # the robots stand on their floors, not sliding sideways under a -Y gravity
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    state, control = model.state(), model.control()
    start = novaphy.world_view(model, state.joint_q)[:, :2].copy()
    for _ in range(100):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, model.timestep)
    np.testing.assert_allclose(novaphy.world_view(model, state.joint_q)[:, :2], start, atol=0.05)


def test_two_given_gravities_that_differ_are_an_error_naming_both():
    scene = novaphy.ModelBuilder(gravity=[0.0, -9.81, 0.0])
    with pytest.raises(ValueError, match=r"add_builder: the added builder's gravity \(0, 0, -9.81\) differs from "
                                         r"the builder's \(0, -9.81, 0\)"):
        scene.replicate(mjcf_robot(), 2)
    given = novaphy.ModelBuilder(gravity=[0.0, -9.81, 0.0])
    with pytest.raises(ValueError, match=r"the file's gravity \(0, 0, -9.81\) differs from the builder's"):
        given.add_mjcf(QUADRUPED)
    # the same gravity given twice, or a gravity set after the import, is no mismatch
    same = novaphy.ModelBuilder(gravity=[0.0, 0.0, -9.81])
    same.replicate(mjcf_robot(), 2)
    moved = mjcf_robot()
    moved.gravity = [0.0, 0.0, 0.0]
    assert list(moved.finalize().gravity) == [0, 0, 0]
    # a builder made without gravity keeps the default where nothing gives one
    plain = novaphy.ModelBuilder()
    pendulum(plain)
    assert not plain.gravity_given and list(plain.finalize().gravity) == [0, -9.81, 0]


def test_a_builder_kept_by_the_build_worlds_callback_stays_valid():
    kept = []

    def build(builder, world):
        kept.append(builder)
        pendulum(builder, world)

    model = novaphy.build_worlds(novaphy.ModelBuilder(), build, novaphy.shard_range(3, 0, 1))
    gc.collect()
    assert model.world_count == 3 and [b.body_count for b in kept] == [1, 1, 1]
    kept[1].add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))  # the kept builder is the callback's own
    assert kept[1].body_count == 2 and kept[1].finalize().body_count == 2
    assert model.body_count == 3


def test_a_state_or_control_of_another_model_with_the_same_counts_is_refused():
    def model(mass):
        builder = novaphy.ModelBuilder()
        link = builder.add_body(novaphy.RigidBody.from_sphere(mass, 0.1))
        builder.add_joint_revolute(-1, link, axis=[0, 1, 0], child_xform=novaphy.Transform([0, 0, 0.5]))
        return builder.finalize()

    a, b = model(1.0), model(2.0)  # the same counts, another mass
    assert a.model_id != b.model_id and a.state().model_id == a.model_id
    solver = novaphy.solvers.SolverFeatherstone(a)
    contacts = novaphy.CollisionPipeline(a).contacts()
    with pytest.raises(ValueError, match="state from another model: made by model"):
        solver.step(b.state(), a.state(), a.control(), contacts, 0.01)
    with pytest.raises(ValueError, match="control from another model: made by model"):
        solver.step(a.state(), a.state(), b.control(), contacts, 0.01)
    with pytest.raises(ValueError, match="state from another model"):
        novaphy.eval_fk(a, b.state())
    # a model finalized alike (the scene rebuilt) is the same model: its states step bit for bit as the first's
    again = model(1.0)
    assert again.model_id == a.model_id
    state, rebuilt = a.state(), again.state()
    state.joint_qd[:] = rebuilt.joint_qd[:] = 1.0
    solver.step(state, state, a.control(), contacts, 0.01)
    solver.step(rebuilt, rebuilt, again.control(), contacts, 0.01)
    assert state.joint_q.tobytes() == rebuilt.joint_q.tobytes()


def test_world_view_refuses_arrays_that_are_not_per_world():
    robot = novaphy.ModelBuilder()
    pendulum(robot)
    robot.add_ground_plane(-1.0)
    scene = novaphy.ModelBuilder()
    scene.replicate(robot, 4)
    model = scene.finalize()
    state = model.state()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    pipeline.collide(state, contacts)
    with pytest.raises(ValueError, match="world_view: contact arrays are not per world"):
        novaphy.world_view(model, contacts.contact_depth)
    with pytest.raises(ValueError, match=r"world_view: Model.articulation_start is not per world"):
        novaphy.world_view(model, model.articulation_start)
    with pytest.raises(ValueError, match="world_view: the array is a part of a State field"):
        novaphy.world_view(model, state.joint_q[1:3])
    with pytest.raises(ValueError, match="none of the model's per-world counts"):
        novaphy.world_view(model, np.zeros(6))
    with pytest.raises(ValueError, match="belongs to another model"):
        other = novaphy.ModelBuilder(gravity=[0.0, 0.0, -1.0])  # the same counts, another gravity
        other.replicate(robot, 4)
        novaphy.world_view(model, other.finalize().state().joint_q)
    assert novaphy.world_view(model, model.shape_mu).shape == (4, 1)
    assert novaphy.world_view(model, state.body_q).shape == (4, 1, 7)
    assert novaphy.world_view(model, np.zeros((4, 3))).shape == (4, 1, 3)  # an array of the user's, one row a body
    shared_floor = novaphy.ModelBuilder()
    shared_floor.add_ground_plane(-1.0)
    shared_floor.replicate(robot_without_floor(), 4)
    with pytest.raises(ValueError, match="shape_mu is not per world .*some shapes are static"):
        floor_model = shared_floor.finalize()
        novaphy.world_view(floor_model, floor_model.shape_mu)


def robot_without_floor():
    robot = novaphy.ModelBuilder()
    pendulum(robot)
    return robot


@pytest.mark.parametrize("call, error, message", [
    (lambda m: novaphy.from_mujoco(m, worlds=0), ValueError, r"from_mujoco\(\): worlds=0 must be in \[1, 2147483647\]"),
    (lambda m: novaphy.from_mujoco(m, worlds=2**31), ValueError, r"worlds=2147483648 must be in"),
    (lambda m: novaphy.from_mujoco(m, precision=1), TypeError, r"precision=1 must be a Precision \(Precision.Float64"),
    (lambda m: novaphy.from_mujoco(m, worlds=None), TypeError, r"worlds=None must be an int, got NoneType"),
])
def test_from_mujoco_names_its_arguments(call, error, message):
    mujoco = pytest.importorskip("mujoco")
    with pytest.raises(error, match=message):
        call(mujoco.MjModel.from_xml_path(QUADRUPED))


def test_arguments_that_do_not_convert_are_named_as_the_user_wrote_them():
    builder = novaphy.ModelBuilder()
    with pytest.raises(ValueError, match=r"ModelBuilder.replicate\(\): world_count=2147483648 is out of the range "
                                         r"of a 32-bit int"):
        builder.replicate(novaphy.ModelBuilder(), 2**31)
    with pytest.raises(TypeError, match=r"ModelBuilder.replicate\(\): other=None must be a ModelBuilder, got None"):
        builder.replicate(None, 2)
    with pytest.raises(TypeError, match=r"ModelBuilder.precision = 1: must be a Precision \(Precision.Float64, "
                                        r"Precision.Float32\), got int"):
        builder.precision = 1
    with pytest.raises(TypeError, match=r"ModelBuilder\(\): gravity=array\(\['a', 'b', 'c'\].*must be an array of "
                                        r"numbers, got an array of str"):
        novaphy.ModelBuilder(gravity=np.array(["a", "b", "c"]))
    with pytest.raises(TypeError, match=r"ModelBuilder.gravity = None: must be an array of 3 numbers, got None"):
        builder.gravity = None
    pendulum(builder)
    model = builder.finalize()
    solver = novaphy.solvers.SolverFeatherstone(model)
    contacts = novaphy.CollisionPipeline(model).contacts()
    state = model.state()
    with pytest.raises(TypeError, match=r"SolverFeatherstone.step\(\): control=None must be a Control, got None"):
        solver.step(state, state, None, contacts, 0.01)
    with pytest.raises(TypeError, match=r"SolverFeatherstone.step\(\): dt='0.01' must be a number, got str"):
        solver.step(state, state, model.control(), contacts, "0.01")
    with pytest.raises(TypeError, match=r"from_numpy: field 'joint_q' must be a numeric array, got an array of dtype "
                                        r"<U1"):
        state.from_numpy({"joint_q": np.array(["a"])})


def test_contacts_of_another_model_with_the_same_counts_are_refused():
    def model(mass):
        builder = novaphy.ModelBuilder()
        link = builder.add_body(novaphy.RigidBody.from_sphere(mass, 0.1))
        builder.add_joint_revolute(-1, link, axis=[0, 1, 0], child_xform=novaphy.Transform([0, 0, 0.5]))
        builder.add_ground_plane(-1.0)
        return builder.finalize()

    a, b = model(1.0), model(2.0)
    other = novaphy.CollisionPipeline(b).contacts()
    with pytest.raises(ValueError, match="contacts buffer is from another model"):
        novaphy.solvers.SolverFeatherstone(a).step(a.state(), a.state(), a.control(), other, 0.01)
    with pytest.raises(ValueError, match="contacts buffer was not made by this pipeline"):
        novaphy.CollisionPipeline(a).collide(a.state(), other)


def test_a_field_of_width_zero_is_an_empty_view():
    """keyframe_ctrl of a model without actuators is (keyframes, 0): an empty view, not a division by zero."""
    builder = novaphy.ModelBuilder()
    body = builder.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.1, 0.1])))
    builder.add_joint_free(-1, body)
    builder.add_keyframe("start", [0, 1, 0, 0, 0, 0, 1])
    model = builder.finalize()
    assert model.keyframe_ctrl.size == 0
    assert model.keyframe_q.shape == (1, 7)
