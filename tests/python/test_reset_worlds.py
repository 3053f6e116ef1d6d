"""Model.reset_worlds from Python: masks, ids and keyframes, the worlds it leaves alone, and bad input."""
import numpy as np
import pytest

import novaphy


@pytest.fixture
def worlds(scene):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(scene("quadruped.xml"))
    alone = robot.finalize()
    robot.add_keyframe("crouch", alone.joint_q0 * 0.5)
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, 4)
    model = builder.finalize()
    state = model.state()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    control = model.control()
    for _ in range(40):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 0.002)
    return model, state


def test_a_mask_or_ids_reset_those_worlds_and_no_other(worlds):
    model, state = worlds
    assert not state.world_reset.any()  # (a step writes 0)
    before = state.copy()
    fresh = model.state()
    model.reset_worlds(state, np.array([False, True, False, True]))
    q, q0 = novaphy.world_view(model, state.joint_q), novaphy.world_view(model, before.joint_q)
    body_q = novaphy.world_view(model, state.body_q)
    np.testing.assert_array_equal(q[[0, 2]], q0[[0, 2]])
    np.testing.assert_array_equal(q[[1, 3]], novaphy.world_view(model, fresh.joint_q)[[1, 3]])
    np.testing.assert_array_equal(body_q[[1, 3]], novaphy.world_view(model, fresh.body_q)[[1, 3]])
    np.testing.assert_array_equal(body_q[[0, 2]], novaphy.world_view(model, before.body_q)[[0, 2]])
    assert not novaphy.world_view(model, state.joint_qd)[[1, 3]].any()
    np.testing.assert_array_equal(state.world_reset, [0, 1, 0, 1])
    # ids, a list, and a keyframe by name and by index
    model.reset_worlds(state, [2], "crouch")
    crouch = model.state(keyframe="crouch")
    np.testing.assert_array_equal(q[2], novaphy.world_view(model, crouch.joint_q)[2])
    model.reset_worlds(state, np.array([0], dtype=np.uint8), 0)
    np.testing.assert_array_equal(q[0], novaphy.world_view(model, crouch.joint_q)[0])
    np.testing.assert_array_equal(state.world_reset, [1, 1, 1, 1])


def test_bad_worlds_and_keyframes_are_named(worlds):
    model, state = worlds
    before = state.to_numpy()
    with pytest.raises(ValueError, match=r"reset_worlds: the mask has shape \(3,\), the model has 4 worlds"):
        model.reset_worlds(state, np.zeros(3, dtype=bool))
    with pytest.raises(IndexError, match=r"reset_worlds: worlds\[1\] = 4 is not a world of the model \(0 .. 3\)"):
        model.reset_worlds(state, [0, 4])
    with pytest.raises(IndexError, match=r"worlds\[0\] = -1"):
        model.reset_worlds(state, [-1])
    with pytest.raises(TypeError, match="reset_worlds: worlds must be a bool mask or world ids, got an array of "
                                        "dtype float64"):
        model.reset_worlds(state, [0.5])
    with pytest.raises(ValueError, match="no keyframe 'stand': the model has 'crouch'"):
        model.reset_worlds(state, [0], "stand")
    with pytest.raises(ValueError, match="keyframe 3 is not one of the model's 1 keyframes"):
        model.reset_worlds(state, [0], 3)
    other = novaphy.ModelBuilder()
    other.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    with pytest.raises(ValueError, match="state"):
        model.reset_worlds(other.finalize().state(), [0])
    after = state.to_numpy()
    for name in before:
        np.testing.assert_array_equal(after[name], before[name], err_msg=name)


def test_restart_worlds_starts_them_from_the_coordinates_written(worlds):
    """A start of the caller's own (a pose turned about z, moving): those worlds' bodies by FK as a new state's
    with the same coordinates, their flags set, every other world as it was; the quaternion normalised."""
    model, state = worlds
    before = state.copy()
    q, qd = novaphy.world_view(model, state.joint_q), novaphy.world_view(model, state.joint_qd)
    start_q = np.array(novaphy.world_view(model, model.joint_q0)[1])
    start_q[3:7] = [0.0, 0.0, 2 * np.sin(0.4), 2 * np.cos(0.4)]  # [x y z w], norm 2
    start_qd = np.linspace(-0.5, 0.5, qd.shape[1])
    q[1], qd[1] = start_q, start_qd
    model.restart_worlds(state, [1])
    start_q[3:7] /= 2
    np.testing.assert_allclose(q[1], start_q, rtol=0, atol=1e-15)
    fresh = model.state()  # (with the coordinates restart_worlds left, the normalisation's last bit its own)
    novaphy.world_view(model, fresh.joint_q)[1] = q[1]
    novaphy.world_view(model, fresh.joint_qd)[1] = start_qd
    novaphy.eval_fk(model, fresh)
    for name in ("joint_q", "joint_qd", "body_q", "body_qd"):
        now, new, old = (novaphy.world_view(model, getattr(s, name)) for s in (state, fresh, before))
        np.testing.assert_array_equal(now[1], new[1], err_msg=name)
        np.testing.assert_array_equal(now[[0, 2, 3]], old[[0, 2, 3]], err_msg=name)
    assert not novaphy.world_view(model, state.body_f)[1].any()
    np.testing.assert_array_equal(state.world_reset, [0, 1, 0, 0])


def test_restart_worlds_names_bad_values_and_writes_nothing(worlds):
    model, state = worlds
    q = novaphy.world_view(model, state.joint_q)
    q[2, 3:7] = 0.0
    before = state.to_numpy()
    with pytest.raises(ValueError, match=r"restart_worlds: the quaternion joint_q\[\d+:\d+\] of joint '.*' "
                                         r"\(world 2\) is zero"):
        model.restart_worlds(state, np.array([False, False, True, False]))
    q[2, 3:7] = [0.0, 0.0, 0.0, 1.0]
    novaphy.world_view(model, state.joint_qd)[3, 0] = np.nan
    with pytest.raises(ValueError, match=r"restart_worlds: joint_qd\[\d+\] \(world 3\) is not finite: nan"):
        model.restart_worlds(state, [3])
    with pytest.raises(IndexError, match=r"restart_worlds: worlds\[0\] = 9 is not a world of the model \(0 .. 3\)"):
        model.restart_worlds(state, [9])
    after = state.to_numpy()
    for name in ("body_q", "body_qd", "world_reset"):
        np.testing.assert_array_equal(after[name], before[name], err_msg=name)
