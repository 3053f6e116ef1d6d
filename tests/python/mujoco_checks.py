"""Checks of a compiled mujoco.MjModel against NovaPhy's import of it, shared by the tests of today's MuJoCo
and tools/menagerie_report.py (imports mujoco only when called)."""

import os
import warnings

import numpy as np

import novaphy


def quiet(fn, *args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args)


def by_file(path, worlds, precision):
    robot = novaphy.ModelBuilder()
    quiet(robot.add_mjcf, path)
    batch = novaphy.ModelBuilder(gravity=robot.gravity)
    batch.precision = precision
    batch.replicate(robot, worlds)
    return batch.finalize()


def shared_robot(name, file):
    """the path of a robot's scene among the Menagerie robots on disk (MENAGERIE_ROOT: ../shared/robots by default
    in the ctest run), else the test is skipped"""
    import pytest

    root = os.environ.get("MENAGERIE_ROOT", "")
    path = os.path.join(root, name, file)
    if not root or not os.path.isfile(path):
        pytest.skip(f"{name} is not on disk (MENAGERIE_ROOT)")
    return path


def by_route(m, path, route):
    """NovaPhy's import of the compiled model m (route "from_mujoco") or of its file `path` through add_mjcf, and
    the map of today's compile (both routes lay the joints and actuators out alike: it serves both)"""
    imported = novaphy.ModelBuilder().add_mujoco_model(m)
    builder = novaphy.ModelBuilder()
    if route == "from_mujoco":
        builder.add_mujoco_model(m)
    else:
        builder.add_mjcf(str(path))
    return imported, builder.finalize()


def start_from_first_keyframe(model):
    key = model.keyframes[0] if model.keyframes else None
    return model.state(keyframe=key), model.control(keyframe=key)


def run(model, steps, dt):
    """The joint_q and joint_qd after `steps` steps of dt from the model's first keyframe (if any)."""
    state, control = start_from_first_keyframe(model)
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, dt)
    return np.array(state.joint_q), np.array(state.joint_qd)


def random_state(m, d, rng):
    import mujoco

    mujoco.mj_resetData(m, d)
    for j in range(m.njnt):
        a = m.jnt_qposadr[j]
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            d.qpos[a : a + 3] = rng.standard_normal(3)
            d.qpos[a + 3 : a + 7] = rng.standard_normal(4)
            d.qpos[a + 3 : a + 7] /= np.linalg.norm(d.qpos[a + 3 : a + 7])
        elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
            d.qpos[a : a + 4] = rng.standard_normal(4)
            d.qpos[a : a + 4] /= np.linalg.norm(d.qpos[a : a + 4])
        else:
            d.qpos[a] = rng.uniform(-1, 1)
    d.qvel[:] = rng.standard_normal(m.nv)
    d.ctrl[:] = rng.uniform(-1, 1, m.nu)


def largest_dynamics_difference(m, states=5):
    """NovaPhy's forward dynamics against mj_forward's qacc with constraints off, actuators on: the largest
    difference over random states, relative to the largest |qacc|."""
    import mujoco

    builder = novaphy.ModelBuilder()
    imported = quiet(builder.add_mujoco_model, m)
    model = builder.finalize()
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(states):
        random_state(m, d, rng)
        mujoco.mj_forward(m, d)
        state, control = model.state(), model.control()
        state.joint_q[:] = imported.to_joint_q(d.qpos)
        state.joint_qd[:] = imported.to_joint_qd(d.qpos, d.qvel)
        for u, a in enumerate(imported.actuator_map):
            if a >= 0:
                control.actuator_ctrl[a] = d.ctrl[u]
        qdd = novaphy.eval_forward_dynamics(model, state, control)
        expected = imported.to_joint_qd(d.qpos, d.qacc)
        worst = max(worst, np.max(np.abs(qdd - expected)) / max(1.0, np.max(np.abs(expected))))
    return worst


def menagerie_path(name):
    """The directory of Menagerie robot `name` where it is on disk (MENAGERIE_ROOT, or the mujoco_menagerie
    package's cache), else None: nothing is downloaded."""
    import mujoco_menagerie

    robot, cache = mujoco_menagerie.get(name), mujoco_menagerie.Cache()
    if cache.root is not None:
        return cache.root / name if (cache.root / name).is_dir() else None
    return cache.model_path(robot) if cache.is_cached(robot) else None


def menagerie_entries():
    """(robot, entry) of every Menagerie robot's default scene, and of its hand where it has one on its own"""
    import mujoco_menagerie

    entries = []
    for name in mujoco_menagerie.names():
        robot = mujoco_menagerie.get(name)
        entries.append((name, robot.default_scene))
        if "hand" in robot.entry_names:
            entries.append((name, "hand"))
    return entries


def one_second_from_keyframe(m, model, imported):
    """NovaPhy and today's MuJoCo each step 1 s from the model's first keyframe (qpos0 without one), commands
    held: NovaPhy's state is finite, and the largest difference of their joint coordinates (MuJoCo's qpos) after it"""
    import mujoco

    d = mujoco.MjData(m)
    if m.nkey > 0:
        mujoco.mj_resetDataKeyframe(m, d, 0)
    steps = round(1.0 / m.opt.timestep)
    q, _ = run(model, steps, m.opt.timestep)
    mujoco.mj_step(m, d, steps)
    return bool(np.all(np.isfinite(q))), float(np.max(np.abs(imported.to_qpos(q) - d.qpos)))


def menagerie_status(name, path, entry):
    """What each route makes of one Menagerie robot: a dict of the checks the docs' table reports."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path / entry.file))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        builder = novaphy.ModelBuilder()
        imported = builder.add_mujoco_model(m)
    model = builder.finalize()
    status = {"robot": name, "file": entry.file, "warnings": [str(w.message) for w in caught]}
    try:
        quiet(novaphy.ModelBuilder().add_mjcf, str(path / entry.file))
        status["mjcf"] = "loads"
        # both routes stepped 1 s from the first keyframe, two worlds each, float32: the same bits?
        steps = round(1.0 / m.opt.timestep)
        from_model = run(quiet(novaphy.from_mujoco, m, 2, novaphy.Precision.Float32), steps, m.opt.timestep)
        from_file = run(by_file(str(path / entry.file), 2, novaphy.Precision.Float32), steps, m.opt.timestep)
        status["same_bits"] = all(a.tobytes() == b.tobytes() for a, b in zip(from_model, from_file))
    except ValueError as e:
        status["mjcf"] = str(e)
        status["same_bits"] = False
    status["finite"], status["qpos_difference_1s"] = one_second_from_keyframe(m, model, imported)
    status["dynamics"] = largest_dynamics_difference(mujoco.MjModel.from_xml_path(str(path / entry.file)))
    return status
