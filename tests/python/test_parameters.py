"""Model.set_parameter from Python: per-world parameters laid out as world_view lays out the field, read by the next
step (a heavier world sinks deeper into a soft floor), topology refused, and bad values named."""
import numpy as np
import pytest

import novaphy


@pytest.fixture
def model(scene):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(scene("quadruped.xml"))
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, 4)
    return builder.finalize()


def run(model, steps=200):
    state = model.state()
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    control = model.control()
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, 0.002)
    return state


def test_values_take_world_views_layout_and_only_the_worlds_given(model):
    mass = novaphy.world_view(model, model.body_mass).copy()
    model.set_parameter("body_mass", mass[[2]] * 2, worlds=[2])
    after = novaphy.world_view(model, model.body_mass)
    np.testing.assert_array_equal(after[2], mass[2] * 2)
    np.testing.assert_array_equal(after[[0, 1, 3]], mass[[0, 1, 3]])
    gravity = novaphy.world_view(model, model.world_gravity)
    assert gravity.shape == (4, 1, 3)
    model.set_parameter("world_gravity", np.zeros((2, 1, 3)), worlds=np.array([True, False, False, True]))
    assert not gravity[[0, 3]].any() and gravity[1].any()
    assert "body_mass" in novaphy.Model.parameter_names


def test_the_next_step_reads_them(model):
    # no gravity in world 1: its robot floats where it began while the others fall onto the floor
    begin = novaphy.world_view(model, model.state().joint_q).copy()
    model.set_parameter("world_gravity", [[0.0, 0.0, 0.0]], worlds=[1])
    q = novaphy.world_view(model, run(model, 100).joint_q)
    np.testing.assert_allclose(q[1], begin[1], atol=1e-12)
    assert np.abs(q[0] - begin[0]).max() > 1e-3
    np.testing.assert_array_equal(q[0], q[2])


def test_topology_and_bad_values_are_refused_by_name(model):
    with pytest.raises(ValueError, match="'joint_type' is not a per-world parameter"):
        model.set_parameter("joint_type", [0], worlds=[0])
    with pytest.raises(IndexError, match=r"worlds\[0\] = 9 is not a world"):
        model.set_parameter("body_mass", np.ones(13), worlds=[9])
    with pytest.raises(ValueError, match="the mask has shape"):
        model.set_parameter("body_mass", np.ones(13), worlds=np.array([True, False]))
    mass = novaphy.world_view(model, model.body_mass).copy()
    with pytest.raises(ValueError, match="values for 4 worlds, expected"):
        model.set_parameter("body_mass", mass[:3])
    mass[3, 2] = np.nan
    with pytest.raises(ValueError, match=r"world 3, body \d+ \('[^']*'\): mass is not finite"):
        model.set_parameter("body_mass", mass)
    mass[3, 2] = -1.0
    with pytest.raises(ValueError, match="mass must be > 0"):
        model.set_parameter("body_mass", mass)
    damping = novaphy.world_view(model, model.joint_damping)[[0]].copy()
    damping[0, -1] = -0.5
    with pytest.raises(ValueError, match="must be finite and >= 0, got -0.5"):
        model.set_parameter("joint_damping", damping, worlds=[0])
    with pytest.raises(TypeError, match="values must be numbers"):
        model.set_parameter("body_mass", "heavy", worlds=[0])
    with pytest.raises(ValueError, match="assignment destination is read-only"):
        model.body_mass[0] = 3.0
    np.testing.assert_array_equal(novaphy.world_view(model, model.body_mass)[:, :2],
                                  novaphy.world_view(model, model.body_mass)[[0], :2].repeat(4, 0))
