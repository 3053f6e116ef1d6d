"""A float32 model's State and Control from Python: float32 arrays (numpy views, DLPack without a copy), what the
engine reads and writes through them, and their checkpoints."""
import os

import numpy as np
import pytest

import novaphy

ARM = os.path.join(os.path.dirname(__file__), "models", "arm.xml")  # motors, servos, a tendon; a table to touch
STATE_FLOATS = ("joint_q", "joint_qd", "body_q", "body_qd", "body_f", "sensor_data")
CONTROL_FLOATS = ("joint_f", "actuator_ctrl", "joint_target_pos", "joint_target_vel", "joint_target_ke",
                  "joint_target_kd")


def arms(precision, worlds=3):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(ARM)
    robot.add_sensor("accelerometer", robot.finalize().body_name.index("hand"))
    builder = novaphy.ModelBuilder()
    builder.precision = precision
    builder.replicate(robot, worlds)
    return builder.finalize()


@pytest.fixture(scope="module")
def arm():
    return arms(novaphy.Precision.Float32)


def simulator(model):
    pipeline = novaphy.CollisionPipeline(model)
    return pipeline, pipeline.contacts(), novaphy.solvers.SolverFeatherstone(model)


def test_a_float32_models_arrays_are_float32_and_a_float64_models_float64(arm):
    state, control = arm.state(keyframe="home"), arm.control(keyframe="home")
    for name in STATE_FLOATS:
        assert getattr(state, name).dtype == np.float32, name
    for name in CONTROL_FLOATS:
        assert getattr(control, name).dtype == np.float32, name
    assert state.world_reset.dtype == np.uint8
    assert state.sensor_data.size == 3 * arm.world_count
    np.testing.assert_array_equal(control.actuator_ctrl, arm.keyframe_ctrl[0].astype(np.float32))
    wide = arms(novaphy.Precision.Float64, 1)
    assert wide.state().joint_q.dtype == np.float64 and wide.control().joint_f.dtype == np.float64


def test_what_python_writes_is_what_the_engine_reads(arm):
    """eval_fk computes in double either way: a float32 model's FK of float joint values is the float64 model's of
    the same values, rounded."""
    wide = arms(novaphy.Precision.Float64)
    rng = np.random.default_rng(0)
    state, state64 = arm.state(), wide.state()
    qd = rng.uniform(-1, 1, state.joint_qd.shape).astype(np.float32)
    state.joint_qd[:] = qd
    state64.joint_qd[:] = qd
    novaphy.eval_fk(arm, state)
    novaphy.eval_fk(wide, state64)
    assert np.abs(state.body_qd).max() > 0.1
    np.testing.assert_array_equal(state.body_qd, state64.body_qd.astype(np.float32))


def test_substeps_in_one_call_are_the_bits_of_one_call_each(arm):
    """Each call widens the float32 arrays and rounds its output back: exact, since a float32 model's stepped state
    is floats, so ten calls of one step give the bits of one call of ten."""
    runs = []
    for calls, substeps in ((1, 10), (10, 1)):
        pipeline, contacts, solver = simulator(arm)
        state, control = arm.state(keyframe="home"), arm.control(keyframe="home")
        control.actuator_ctrl[:] += np.float32(0.1)
        for _ in range(calls):
            novaphy.simulate(pipeline, solver, state, control, contacts, substeps)
        runs.append(state)
    assert not np.array_equal(runs[0].joint_q, arm.state(keyframe="home").joint_q)
    for name in STATE_FLOATS:
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name), err_msg=name)


def test_threads_sharing_one_solver_and_one_float32_state_complete_or_raise_writing_nothing():
    """The binding widens a float32 state and rounds it back under the solver's one-call flag, so a step refused on
    another thread touches nothing: the shared state is the bits of the completed steps made one after another."""
    import threading
    model = arms(novaphy.Precision.Float32, 256)
    _, contacts, solver = simulator(model)  # (no collide: no contacts, so every step is the same map)
    solver.settings.num_threads = 1
    state, control = model.state(keyframe="home"), model.control(keyframe="home")
    control.actuator_ctrl[:] += np.float32(0.1)
    runs = [{"done": 0, "refused": 0, "other": []} for _ in range(2)]

    def hammer(run):
        for _ in range(5000):
            try:
                solver.step(state, state, control, contacts, 0.002)
                run["done"] += 1
            except novaphy.Error as e:
                if "called while another call of the same object runs on another thread" in str(e):
                    run["refused"] += 1
                else:
                    run["other"].append(str(e))
            if runs[0]["refused"] + runs[1]["refused"] >= 100:
                return

    threads = [threading.Thread(target=hammer, args=(run,)) for run in runs]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert runs[0]["other"] == [] and runs[1]["other"] == []
    assert runs[0]["refused"] + runs[1]["refused"] > 0  # (the two threads' steps did meet)
    _, own_contacts, own_solver = simulator(model)
    replay = model.state(keyframe="home")
    for _ in range(runs[0]["done"] + runs[1]["done"]):
        own_solver.step(replay, replay, control, own_contacts, 0.002)
    for name in STATE_FLOATS:
        np.testing.assert_array_equal(getattr(state, name), getattr(replay, name), err_msg=name)


def test_step_and_reset_write_the_float32_arrays(arm):
    pipeline, contacts, solver = simulator(arm)
    state, control = arm.state(keyframe="home"), arm.control(keyframe="home")
    out = arm.state()
    pipeline.collide(state, contacts)
    solver.step(state, out, control, contacts, 0.002)
    assert out.sensor_data.any()
    assert not np.array_equal(out.joint_qd, state.joint_qd)
    arm.reset_worlds(out, [1])
    q = novaphy.world_view(arm, out.joint_q)
    np.testing.assert_array_equal(q[1], novaphy.world_view(arm, arm.state().joint_q)[1])
    assert out.world_reset[1] == 1 and not novaphy.world_view(arm, out.sensor_data)[1].any()


def test_checkpoints_keep_the_dtype_and_check_shapes(arm):
    state = arm.state(keyframe="home")
    saved = state.to_numpy()
    assert saved["joint_q"].dtype == np.float32 and saved["world_reset"].dtype == np.uint8
    state.joint_q[:] = 0
    state.from_numpy({"joint_q": saved["joint_q"].astype(np.float64)})
    np.testing.assert_array_equal(state.joint_q, saved["joint_q"])
    with pytest.raises(ValueError, match=r"from_numpy: field 'joint_q' has shape \(3,\), expected"):
        state.from_numpy({"joint_q": np.zeros(3)})
    with pytest.raises(novaphy.Error, match="assign: the other state is float64, this one float32"):
        state.assign(arms(novaphy.Precision.Float64).state())


def test_dlpack_hands_the_arrays_over_without_a_copy(arm):
    state = arm.state()
    shared = np.from_dlpack(state.joint_q)
    state.joint_q[0] = 42.0
    assert shared[0] == 42.0 and np.shares_memory(shared, state.joint_q)


def test_jax_reads_the_arrays_in_place(arm):
    jax = pytest.importorskip("jax")
    state = arm.state()
    body_q = jax.dlpack.from_dlpack(state.body_q)
    assert body_q.dtype == np.float32 and body_q.shape == state.body_q.shape
    state.body_q[0, 0] = 7.0
    assert float(body_q[0, 0]) == 7.0


def test_torch_reads_the_arrays_in_place(arm):
    torch = pytest.importorskip("torch")
    control = arm.control()
    ctrl = torch.from_dlpack(control.actuator_ctrl)
    assert ctrl.dtype == torch.float32
    ctrl[2] = 3.0
    assert control.actuator_ctrl[2] == 3.0
