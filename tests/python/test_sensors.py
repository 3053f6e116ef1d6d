"""Sensors from Python: an MJCF's <sensor> elements imported from today's MuJoCo's compiled model (the route whose
sensor types MuJoCo numbers otherwise than 2.2.2), computed by the step as MuJoCo's sensordata after mj_step, read
per world by name; sensors added by type or name, and bad ones named."""
import os
import warnings

import numpy as np
import pytest

import novaphy

SENSORS_XML = os.path.join(os.path.dirname(__file__), "models", "sensors.xml")


def step(model, state, steps, control=None):
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model, angular_damping=0.0)
    control = control or model.control()
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, model.timestep)


@pytest.mark.parametrize("key, steps", [(0, 1), (1, 200)])
def test_todays_mujoco_route_matches_its_sensordata(key, steps):
    mujoco = pytest.importorskip("mujoco")
    m = mujoco.MjModel.from_xml_path(SENSORS_XML)
    d = mujoco.MjData(m)
    builder = novaphy.ModelBuilder()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imported = builder.add_mujoco_model(m)
    assert any("(magnetometer)" in str(w.message) and "not computed" in str(w.message) for w in caught)
    model = builder.finalize()
    mujoco.mj_resetDataKeyframe(m, d, key)
    state = model.state(keyframe=model.keyframes[key])
    for _ in range(steps):
        mujoco.mj_step(m, d)
    step(model, state, steps)
    start = np.asarray(model.sensor_start)
    for i, s in enumerate(imported.sensor_map):
        kind = mujoco.mjtSensor(m.sensor_type[i]).name
        if s < 0:
            assert kind == "mjSENS_MAGNETOMETER"
            continue
        theirs = d.sensordata[m.sensor_adr[i] : m.sensor_adr[i] + m.sensor_dim[i]]
        ours = np.asarray(state.sensor_data[start[s] : start[s + 1]])
        if kind in ("mjSENS_FRAMEQUAT", "mjSENS_BALLQUAT") and ours @ theirs < 0:
            ours = -ours
        np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-9, err_msg=f"sensor {i} ({kind})")


def test_sensor_view_reads_each_world_by_name():
    robot = novaphy.ModelBuilder()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot.add_mjcf(SENSORS_XML)
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, 3, spacing=(0, 3, 0))
    model = builder.finalize()
    state = model.state(keyframe="resting")
    step(model, state, 200)
    values = novaphy.world_view(model, state.sensor_data)
    assert values.shape == (3, model.sensor_value_count // 3)
    pad = novaphy.sensor_view(model, state, "pad")
    assert pad.shape == (3, 1) and np.shares_memory(pad, state.sensor_data)
    ball = model.body_name.index("ball")
    np.testing.assert_allclose(pad[:, 0], -model.gravity[2] * model.body_mass[ball], rtol=1e-6)
    np.testing.assert_array_equal(novaphy.sensor_view(model, state, "side"), 0)
    with pytest.raises(KeyError, match="no sensor 'nose'"):
        novaphy.sensor_view(model, state, "nose")


def test_add_sensor_by_type_or_name_and_bad_ones_named():
    builder = novaphy.ModelBuilder(gravity=(0, 0, -9.81))
    body = builder.add_body(novaphy.RigidBody(mass=1.0))
    builder.add_joint_revolute(-1, body)
    builder.add_sensor("jointpos", 0, name="angle")
    builder.add_sensor(novaphy.SensorType.ProjectedGravity, body, name="up")
    assert novaphy.SensorType.Gyro.mjcf_name == "gyro"
    with pytest.raises(ValueError, match="no sensor type 'gyroscope'"):
        builder.add_sensor("gyroscope", body)
    with pytest.raises(ValueError, match=r"sensor 2 \('z'\): a ballquat sensor reads a Ball joint"):
        builder.add_sensor("ballquat", 0, name="z")
    with pytest.raises(ValueError, match="only a touch or contactforce sensor reads one shape's contacts"):
        builder.add_sensor("gyro", body, shape=0)
    with pytest.raises(ValueError, match="zone_size must be finite and > 0"):
        builder.add_sensor("touch", body, zone_type=novaphy.ShapeType.Sphere)
    model = builder.finalize()
    assert list(model.sensor_name) == ["angle", "up"]
    state = model.state()
    step(model, state, 1)
    np.testing.assert_allclose(novaphy.sensor_view(model, state, "up")[0], (0, 0, -1), atol=1e-12)
