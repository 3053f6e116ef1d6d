"""SolverFeatherstone and CollisionPipeline through the binding."""

import pathlib
import re

import numpy as np
import pytest

import novaphy

SCENES = pathlib.Path(__file__).resolve().parents[2] / "bench" / "scenes"

SEED_SOLVER_EXAMPLE = '''
import numpy as np
import novaphy

builder = novaphy.ModelBuilder()
builder.add_ground_plane(y=0.0)

# Add a single-link revolute pendulum.
body_idx = builder.add_body(
    novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1], dtype=np.float32)),
)
dof = novaphy.JointDofConfig()
dof.axis = np.array([0, 0, 1], dtype=np.float32)
joint_idx = builder.add_joint_revolute(parent=-1, child=body_idx, axis=dof)
builder.add_articulation([joint_idx])
model = builder.finalize()

solver = novaphy.solvers.SolverFeatherstone(
    model,
    angular_damping=0.05,
    update_mass_matrix_interval=1,
)
state = model.state()
control = model.control()
pipeline = novaphy.CollisionPipeline(model)
contacts = pipeline.contacts()

for _ in range(1000):
    pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, 1.0 / 120.0)
'''

SEED_GUIDE_EXAMPLE = '''
builder = novaphy.ModelBuilder()
builder.add_ground_plane(y=0.0)
body_index = builder.add_body(body)
dof = novaphy.JointDofConfig()
dof.axis = np.array([0, 0, 1], dtype=np.float32)
joint_index = builder.add_joint_revolute(parent=-1, child=body_index, axis=dof)
builder.add_articulation([joint_index])
model = builder.finalize()

solver   = novaphy.solvers.SolverFeatherstone(
    model,
    angular_damping=0.05,
    update_mass_matrix_interval=1,
)
state    = model.state()
control  = model.control()
collision_pipeline = novaphy.CollisionPipeline(model)
contacts = collision_pipeline.contacts()

for _ in range(1000):
    collision_pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, 1.0 / 120.0)
'''


def test_seed_solver_example_runs_verbatim():
    scope = {}
    exec(SEED_SOLVER_EXAMPLE, scope)
    # the box pendulum turns about its own centre: gravity exerts no torque, it stays put
    assert np.all(np.isfinite(scope["state"].joint_q))
    assert abs(scope["state"].joint_q[0]) < 1e-12


def test_seed_guide_example_runs_verbatim():
    scope = {"np": np, "novaphy": novaphy, "body": novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1]))}
    exec(SEED_GUIDE_EXAMPLE, scope)
    assert scope["solver"].settings.update_mass_matrix_interval == 1


def falling_box(**solver_kwargs):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    box = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.2, 0.2, 0.2]), xform=novaphy.Transform([0, 1, 0]))
    builder.add_shape_box(box, [0.2, 0.2, 0.2])
    model = builder.finalize()
    solver = novaphy.solvers.SolverFeatherstone(model, **solver_kwargs)
    pipeline = novaphy.CollisionPipeline(model)
    return model, solver, pipeline, pipeline.contacts(), model.state(), model.control()


def test_box_lands_and_contacts_are_readable():
    model, solver, pipeline, contacts, state, control = falling_box()
    for _ in range(240):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 1.0 / 120.0)
    assert state.body_q[0, 1] == pytest.approx(0.2, abs=solver.settings.linear_slop + 1e-6)
    assert contacts.contact_count == 4
    assert contacts.contact_normal.shape == (4, 3) and contacts.contact_point.shape == (4, 3)
    np.testing.assert_allclose(contacts.contact_normal, [[0, 1, 0]] * 4, atol=1e-12)
    assert set(contacts.contact_body_a) == {-1} and set(contacts.contact_body_b) == {0}
    # the four impulses carry the box's weight over one step
    np.testing.assert_allclose(contacts.contact_impulse[:, 1].sum(), 9.81 / 120.0, rtol=1e-3)


def test_settings_mirror_the_constructor_and_are_writable():
    _, solver, *_ = falling_box(angular_damping=0.1, update_mass_matrix_interval=3, friction_smoothing=0.5,
                                use_tile_gemm=True, fuse_cholesky=False)
    s = solver.settings
    assert (s.angular_damping, s.update_mass_matrix_interval, s.friction_smoothing) == (0.1, 3, 0.5)
    assert s.use_tile_gemm and not s.fuse_cholesky
    s.num_iterations = 50
    s.linear_slop = 0.002
    assert solver.settings.num_iterations == 50 and solver.settings.linear_slop == 0.002
    s.pgs_tolerance = 1e-5
    assert solver.settings.pgs_tolerance == 1e-5
    assert s.stream_body_output_above == 2 << 20
    s.stream_body_output_above = 0
    assert solver.settings.stream_body_output_above == 0
    for name in ["erp", "cfm", "warmstarting_factor", "restitution_threshold", "use_warmstarting"]:
        assert hasattr(s, name)


def test_joint_support_is_queryable():
    _, solver, *_ = falling_box()
    support = solver.joint_support()
    assert support["Revolute"] and support["Slide"] and support.supports("Free")
    assert not support["D6"] and not support["Distance"] and not support["Cable"]
    assert "Cable: no" in str(support)


def test_bad_step_arguments():
    model, solver, pipeline, contacts, state, control = falling_box()
    with pytest.raises(ValueError, match="dt must be finite and > 0"):
        solver.step(state, state, control, contacts, 0.0)
    with pytest.raises(ValueError, match="dt must be finite and > 0"):
        solver.step(state, state, control, contacts, float("nan"))
    with pytest.raises(ValueError, match="contacts buffer is from another model"):
        solver.step(state, state, control, contacts_from(), 0.01)
    with pytest.raises(ValueError, match="contacts buffer was not made by this pipeline"):
        pipeline.collide(state, contacts_from())
    solver.settings.erp = 2.0
    with pytest.raises(ValueError, match=r"settings.erp must be in \[0, 1\], got 2"):
        solver.step(state, state, control, contacts, 0.01)
    solver.settings.erp = 0.2
    solver.settings.num_iterations = -3
    with pytest.raises(ValueError, match="settings.num_iterations must be >= 0, got -3"):
        solver.step(state, state, control, contacts, 0.01)
    solver.settings.num_iterations = 20
    solver.settings.pgs_tolerance = -1.0
    with pytest.raises(ValueError, match=r"settings.pgs_tolerance must be in \[0, 1000000\], got -1"):
        solver.step(state, state, control, contacts, 0.01)


def contacts_from():
    """Contacts of a model with a different number of shapes."""
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    builder.add_ground_plane(1.0)
    builder.add_ground_plane(2.0)
    builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))
    model = builder.finalize()
    return novaphy.CollisionPipeline(model).contacts()


def test_pd_drive_through_control_views():
    builder = novaphy.ModelBuilder(gravity=[0, 0, 0])
    arm = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
    builder.add_joint_revolute(-1, arm, axis=[0, 0, 1], target_ke=100.0, target_kd=20.0)
    model = builder.finalize()
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts, state, control = pipeline.contacts(), model.state(), model.control()
    assert control.joint_target_ke[0] == 100.0
    control.joint_target_pos[0] = 0.5
    for _ in range(600):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 1.0 / 120.0)
    assert state.joint_q[0] == pytest.approx(0.5, rel=1e-3)


def test_divergence_guard_flags_an_unstable_robot_among_stable_ones():
    builder = novaphy.ModelBuilder()
    for k in range(4):
        link = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
        builder.add_joint_revolute(-1, link, axis=[0, 0, 1], parent_xform=novaphy.Transform([k, 2.0, 0.0]),
                                   child_xform=novaphy.Transform([-0.25, 0.0, 0.0]))
    model = builder.finalize()
    solver = novaphy.solvers.SolverFeatherstone(model)
    assert solver.settings.on_divergence == novaphy.solvers.DivergencePolicy.Flag
    pipeline = novaphy.CollisionPipeline(model)
    contacts, state, control = pipeline.contacts(), model.state(), model.control()
    state.joint_qd[1] = 5e6  # beyond settings.divergence_speed
    pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, 1.0 / 120.0)
    np.testing.assert_array_equal(solver.diverged, [0, 1, 0, 0])
    assert state.joint_qd[1] == 5e6 and np.all(np.isfinite(state.joint_q))
    solver.settings.on_divergence = novaphy.solvers.DivergencePolicy.Reset
    solver.step(state, state, control, contacts, 1.0 / 120.0)
    assert state.joint_qd[1] == 0.0 and state.joint_q[1] == 0.0
    solver.settings.on_divergence = novaphy.solvers.DivergencePolicy.Raise
    state.joint_qd[1] = 5e6
    with pytest.raises(ValueError, match="step diverged in articulation 1"):
        solver.step(state, state, control, contacts, 1.0 / 120.0)


def test_settings_object_on_its_own():
    settings = novaphy.solvers.SolverFeatherstoneSettings()
    assert settings.num_iterations == 20 and settings.erp == 0.2 and settings.fuse_cholesky
    assert settings.on_divergence == novaphy.solvers.DivergencePolicy.Flag and settings.num_threads == 0
    _, solver, *_ = falling_box()
    settings.num_iterations = 7
    solver.settings = settings
    assert solver.settings.num_iterations == 7


def pendulum_grid(precision, worlds=20):
    robot = novaphy.ModelBuilder()
    body = robot.add_body(novaphy.RigidBody.from_box(1.0, np.array([0.1, 0.5, 0.1])))
    dof = novaphy.JointDofConfig()
    dof.axis = np.array([0.0, 0.0, 1.0])
    robot.add_articulation([robot.add_joint_revolute(parent=-1, child=body, axis=dof)])
    batch = novaphy.ModelBuilder()
    batch.precision = precision
    batch.replicate(robot, worlds)
    return batch.finalize()


def swing(model, batched=True, steps=200, use_tile_gemm=False):
    solver = novaphy.solvers.SolverFeatherstone(model, use_tile_gemm=use_tile_gemm)
    solver.settings.use_batch_kernels = batched
    state, control = model.state(), model.control()
    state.joint_qd[:] = np.linspace(-2, 2, model.joint_dof_count)
    contacts = novaphy.CollisionPipeline(model).contacts()
    for _ in range(steps):
        solver.step(state, state, control, contacts, 1.0 / 240.0)
    return solver, state


def test_tiled_mass_matrix_steps_like_crba_on_the_batched_path():
    model = pendulum_grid(novaphy.Precision.Float64)
    _, crba = swing(model)
    _, tiled = swing(model, use_tile_gemm=True)
    _, scalar_tiled = swing(model, batched=False, use_tile_gemm=True)
    np.testing.assert_allclose(tiled.joint_q, crba.joint_q, atol=1e-12)
    np.testing.assert_allclose(scalar_tiled.joint_q, crba.joint_q, atol=1e-12)


def test_batched_precisions_follow_the_scalar_kernels():
    model64 = pendulum_grid(novaphy.Precision.Float64)
    assert model64.precision == novaphy.Precision.Float64
    solver, batched = swing(model64)
    _, scalar = swing(model64, batched=False)
    np.testing.assert_allclose(batched.joint_q, scalar.joint_q, atol=1e-12)
    assert solver.memory_bytes > 0
    model32 = pendulum_grid(novaphy.Precision.Float32)
    assert model32.precision == novaphy.Precision.Float32
    _, single = swing(model32)
    # float32 steps round the state to float each step: close to float64, and exactly representable
    np.testing.assert_allclose(single.joint_q, scalar.joint_q, atol=1e-4)
    assert np.array_equal(single.joint_q.astype(np.float32).astype(np.float64), single.joint_q)


def test_collision_threads_find_the_same_contacts():
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane()
    body = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.2, 0.2, 0.2]))
    builder.add_shape_box(body, [0.2, 0.2, 0.2])
    worlds = novaphy.ModelBuilder()
    worlds.replicate(builder, 8)
    model = worlds.finalize()
    found = []
    for threads in (1, 2):
        pipeline = novaphy.CollisionPipeline(model, num_threads=threads)
        contacts = pipeline.contacts()
        pipeline.collide(model.state(), contacts)
        found.append((contacts.contact_shape_b.copy(), contacts.contact_point.copy()))
    assert len(found[0][0]) == 32
    np.testing.assert_array_equal(found[0][0], found[1][0])
    np.testing.assert_array_equal(found[0][1], found[1][1])
    with pytest.raises(ValueError, match="num_threads must be >= 0"):
        novaphy.CollisionPipeline(model, num_threads=-1)


def test_a_position_servo_holds_its_target_and_its_force_needs_the_state():
    builder = novaphy.ModelBuilder(gravity=[0.0, 0.0, 0.0])
    link = builder.add_body(novaphy.RigidBody.from_box(0.1, [0.1, 0.02, 0.02]))
    joint = builder.add_joint_revolute(parent=-1, child=link, axis=[0.0, 0.0, 1.0],
                                       child_xform=novaphy.Transform([-0.1, 0, 0]))
    servo = builder.add_position(joint, kp=1e4, kv=5.0, force_lower=-1e4, force_upper=1e4, name="servo")
    model = builder.finalize()
    assert model.actuator_gain[servo] == 1e4 and list(model.actuator_bias[servo]) == [0.0, -1e4, -5.0]
    state, control = model.state(), model.control()
    control.actuator_ctrl[servo] = 2.0
    with pytest.raises(ValueError, match="needs the state"):
        novaphy.eval_control_force(model, control)
    assert novaphy.eval_control_force(model, control, state)[0] == 1e4  # clamped at its force range
    control.actuator_ctrl[servo] = 0.7
    solver = novaphy.solvers.SolverFeatherstone(model, angular_damping=0.0)
    contacts = novaphy.CollisionPipeline(model).contacts()
    for _ in range(180):
        solver.step(state, state, control, contacts, 1.0 / 60.0)
    assert state.joint_q[0] == pytest.approx(0.7, abs=1e-6)


def test_tendons_and_equalities_from_python():
    # a slide on a slide: a servo on their tendon (the sum), the second coupled to mirror the first
    builder = novaphy.ModelBuilder(gravity=[0.0, 0.0, 0.0])
    parent, joints = -1, []
    for _ in range(2):
        body = builder.add_body(novaphy.RigidBody.from_box(0.1, [0.01, 0.01, 0.01]))
        joints.append(builder.add_joint_prismatic(parent=parent, child=body, axis=[1.0, 0.0, 0.0]))
        parent = body
    tendon = builder.add_tendon(joints, [1.0, 1.0], damping=0.1, name="sum")
    servo = builder.add_tendon_actuator(tendon, gain=50.0, bias=[0.0, -50.0, -5.0], name="servo")
    builder.add_joint_coupling(joints[1], joints[0], [0.0, 1.0, 0.0, 0.0, 0.0], name="mirror")
    model = builder.finalize()
    assert model.tendon_count == 1 and model.tendon_name == ["sum"] and model.equality_name == ["mirror"]
    assert model.actuator_joint[servo] == -1 and model.actuator_tendon[servo] == tendon
    state, control = model.state(), model.control()
    control.actuator_ctrl[servo] = 0.06
    solver = novaphy.solvers.SolverFeatherstone(model)
    contacts = novaphy.CollisionPipeline(model).contacts()
    for _ in range(2000):
        solver.step(state, state, control, contacts, 0.002)
    assert state.joint_q[0] + state.joint_q[1] == pytest.approx(0.06, abs=1e-4)
    assert state.joint_q[1] == pytest.approx(state.joint_q[0], abs=1e-5)
    with pytest.raises(ValueError, match="tendon 1: joint index 5 out of range"):
        builder.add_tendon([5], [1.0])


def test_a_weld_from_python_holds_a_body_in_the_air():
    builder = novaphy.ModelBuilder()
    body = builder.add_body(novaphy.RigidBody.from_box(1.0, [0.1, 0.1, 0.1]), xform=novaphy.Transform([0.0, 2.0, 0.0]))
    builder.add_weld(body, -1, name="hook", anchor=[0.1, 0.0, 0.0])
    model = builder.finalize()
    assert model.equality_count == 1 and model.equality_name == ["hook"]
    state = model.state()
    solver = novaphy.solvers.SolverFeatherstone(model)
    contacts = novaphy.CollisionPipeline(model).contacts()
    for _ in range(500):
        solver.step(state, state, model.control(), contacts, 0.002)
    assert np.allclose(state.body_q[body][:3], [0.0, 2.0, 0.0], atol=1e-3)
    with pytest.raises(ValueError, match=r"equality 1 \('again'\) \(weld\): welds body 0 to itself"):
        builder.add_weld(body, body, name="again")


def test_mujocos_friction_rule_from_python():
    builder = novaphy.ModelBuilder()
    builder.friction_rule = novaphy.FrictionRule.Mujoco
    bodies = [builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1)) for _ in range(2)]
    builder.add_shape_sphere(bodies[0], 0.1, mu=0.2, priority=1, condim=1)
    builder.add_shape_sphere(bodies[1], 0.1, mu=0.9)
    model = builder.finalize()
    assert model.friction_rule == novaphy.FrictionRule.Mujoco
    assert list(model.shape_priority) == [1, 0] and list(model.shape_condim) == [1, 3]
    with pytest.raises(ValueError, match="condim must be 1, 3, 4 or 6, got 5"):
        builder.add_shape_sphere(bodies[1], 0.1, condim=5)


def box_worlds(worlds=64):
    robot = novaphy.ModelBuilder()
    robot.add_ground_plane()
    box = robot.add_body(novaphy.RigidBody.from_box(1.0, [0.2, 0.2, 0.2]), xform=novaphy.Transform([0.0, 0.19, 0.0]))
    robot.add_shape_box(box, [0.2, 0.2, 0.2])
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, worlds)
    return builder.finalize()


def test_threads_sharing_one_solver_and_pipeline_complete_or_raise():
    import threading
    model = box_worlds(256)
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.num_threads = 1
    pipeline = novaphy.CollisionPipeline(model, num_threads=1)
    control = model.control()
    runs = [{"state": model.state(), "contacts": pipeline.contacts(), "calls": "", "refused": 0, "other": []}
            for _ in range(2)]
    busy = re.compile(r"^(SolverFeatherstone\.step|CollisionPipeline\.collide) called while another call of the same "
                      r"object runs on another thread \(use one object per thread\)$")

    def hammer(run):
        for _ in range(60):
            try:
                pipeline.collide(run["state"], run["contacts"])
                run["calls"] += "c"
                solver.step(run["state"], run["state"], control, run["contacts"], 1.0 / 120.0)
                run["calls"] += "s"
            except ValueError as e:
                if busy.match(str(e)):
                    run["refused"] += 1
                else:
                    run["other"].append(str(e))

    threads = [threading.Thread(target=hammer, args=(run,)) for run in runs]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for run in runs:
        assert run["other"] == []
        assert run["calls"].count("s") + run["refused"] == 60
        # the calls that completed, replayed on a solver and pipeline of its own: the same bits
        own_solver = novaphy.solvers.SolverFeatherstone(model)
        own_pipeline = novaphy.CollisionPipeline(model)
        state, contacts = model.state(), own_pipeline.contacts()
        for call in run["calls"]:
            if call == "c":
                own_pipeline.collide(state, contacts)
            else:
                own_solver.step(state, state, control, contacts, 1.0 / 120.0)
        np.testing.assert_array_equal(run["state"].joint_q, state.joint_q)
        np.testing.assert_array_equal(run["state"].joint_qd, state.joint_qd)


def test_a_contact_buffer_too_small_grows_raises_or_drops():
    model = box_worlds(4)  # 16 contacts: four corners a box
    pipeline = novaphy.CollisionPipeline(model, contact_capacity=10)
    contacts, state = pipeline.contacts(), model.state()
    old_view = contacts.contact_depth
    pipeline.collide(state, contacts)
    assert (contacts.contact_count, contacts.contact_capacity, contacts.contact_dropped) == (16, 20, 0)
    assert old_view.shape == (0,)  # an old view stays valid (its memory kept), showing what it showed
    np.testing.assert_allclose(contacts.contact_depth, 0.01)
    raising = novaphy.CollisionPipeline(model, contact_capacity=10, on_overflow=novaphy.ContactOverflow.Raise)
    small = raising.contacts()
    with pytest.raises(ValueError, match=r"contact capacity 10 is too small: collide found 16 contacts \(make the "
                                         r"pipeline with contact_capacity >= 16, or on_overflow Grow\)"):
        raising.collide(state, small)
    assert small.contact_count == 0
    dropping = novaphy.CollisionPipeline(model, contact_capacity=10, on_overflow=novaphy.ContactOverflow.Drop)
    dropped = dropping.contacts()
    dropping.collide(state, dropped)
    assert (dropped.contact_count, dropped.contact_dropped) == (10, 6)


def motor_worlds():
    robot = novaphy.ModelBuilder()
    link = robot.add_body(novaphy.RigidBody.from_box(1.0, [0.05, 0.25, 0.05]))
    joint = robot.add_joint_revolute(-1, link, axis=[0, 0, 1], child_xform=novaphy.Transform([-0.25, 0.0, 0.0]))
    robot.add_motor(joint, gear=1.0, ctrl_lower=-1.0, ctrl_upper=1.0)
    robot.add_keyframe("swing", [0.7], [-1.5])
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, 4)
    return builder.finalize()


def test_non_finite_commands_and_negative_gains_raise_naming_entry_world_and_value():
    model = motor_worlds()
    solver = novaphy.solvers.SolverFeatherstone(model)
    contacts = novaphy.CollisionPipeline(model).contacts()
    for bad, text in [(np.inf, "inf"), (-np.inf, "-inf"), (np.nan, "nan")]:
        state, control = model.state(), model.control()
        control.actuator_ctrl[2] = bad
        with pytest.raises(ValueError, match=rf"actuator_ctrl\[2\] is not finite: {text} \(world 2\)"):
            solver.step(state, state, control, contacts, 1.0 / 120.0)
        assert state.joint_q[2] == 0.0 and state.joint_q[1] != 0.0  # that world left as it was, the others stepped
    state, control = model.state(), model.control()
    control.joint_target_kd[3] = -2.0
    with pytest.raises(ValueError, match=r"joint_target_kd\[3\] must be >= 0 \(as the builder's gains\), got -2 "
                                         r"\(world 3\)"):
        solver.step(state, state, control, contacts, 1.0 / 120.0)


def test_reset_restarts_a_diverged_world_at_the_named_keyframe():
    model = motor_worlds()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.on_divergence = novaphy.solvers.DivergencePolicy.Reset
    solver.set_reset_keyframe("swing")
    state, control = model.state(), model.control()
    contacts = novaphy.CollisionPipeline(model).contacts()
    for _ in range(10):
        solver.step(state, state, control, contacts, 1.0 / 120.0)
    state.joint_qd[2] = 5e6
    solver.step(state, state, control, contacts, 1.0 / 120.0)
    np.testing.assert_array_equal(solver.diverged, [0, 0, 1, 0])
    assert state.joint_q[2] == 0.7 and state.joint_qd[2] == -1.5
    with pytest.raises(ValueError, match="stand"):
        solver.set_reset_keyframe("stand")


def test_the_quadruped_at_one_second_steps_is_flagged_once_its_contacts_are_too_deep():
    builder = novaphy.ModelBuilder()
    builder.add_mjcf(str(SCENES / "quadruped.xml"))
    model = builder.finalize()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.on_divergence = novaphy.solvers.DivergencePolicy.Raise
    pipeline = novaphy.CollisionPipeline(model)
    state, control, contacts = model.state(), model.control(), pipeline.contacts()
    pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, 1.0)  # through the floor: no contact showed it coming
    pipeline.collide(state, contacts)
    assert contacts.contact_depth.max() > solver.settings.divergence_depth
    with pytest.raises(ValueError, match=r"step diverged in articulation 0: a contact .* m deep, beyond "
                                         r"divergence_depth 0.5 m"):
        solver.step(state, state, control, contacts, 1.0)
