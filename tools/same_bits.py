"""A hash of each scene's state after 150 steps of 37 worlds (the gripper: one) (a SIMD block's remainder included), float32 and
float64, with a push at step 50: two builds that print the same lines stepped the same bits. For a change that
means to keep the arithmetic (a move, a rename, a split).
    PYTHONPATH=build/python build/venv/bin/python tools/same_bits.py > before.txt   (then after, and diff)"""
import hashlib
import sys
import warnings

import numpy as np

import novaphy

ROBOTS = "../shared/robots"
SCENES = [
    (f"{ROBOTS}/unitree_go1/scene.xml", None),  # frictionloss, condim 6 feet, limits
    ("bench/scenes/quadruped.xml", None),
    ("/usr/share/mujoco/model/humanoid/humanoid.xml", None),
    ("bench/scenes/box_drop.xml", None),
    (f"{ROBOTS}/franka_emika_panda/scene.xml", None),  # an equality and a tendon on the fingers: the islands
    (f"{ROBOTS}/wonik_allegro/scene_right.xml", None),
    ("tests/python/models/gripper.xml", None),  # a tendon joining two articulations, a joint equality (one world)
    ("tests/python/models/hand.xml", None),  # condim 6, soft contacts, tendons
    ("tests/python/models/arm.xml", None),  # limits, frictionloss, condim 4, a joint equality
]


def state_hash(scene, keyframe, precision):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        builder = novaphy.ModelBuilder()
        builder.precision = precision
        robot = novaphy.ModelBuilder()
        robot.add_mjcf(scene)
        builder.replicate(robot, 1 if "gripper" in scene else 37)  # (its tendon joins articulations)
        model = builder.finalize()
    key = keyframe or (model.keyframes[0] if model.keyframes else None)
    state = model.state(keyframe=key) if key else model.state()
    control = model.control(keyframe=key) if key else model.control()
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    rng = np.random.default_rng(1)
    dt = model.timestep if model.timestep > 0 else 0.002
    for k in range(150):
        if k == 50:
            qd = np.array(state.joint_qd)
            state.joint_qd[:] = qd + 0.3 * rng.standard_normal(qd.shape)
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, dt)
    bits = np.ascontiguousarray(state.joint_q).tobytes() + np.ascontiguousarray(state.joint_qd).tobytes()
    return hashlib.sha1(bits).hexdigest()[:16]


def main():
    for scene, keyframe in SCENES:
        for precision in (novaphy.Precision.Float32, novaphy.Precision.Float64):
            name = "/".join(scene.split("/")[-2:])
            print(f"{name} {precision.name} {state_hash(scene, keyframe, precision)}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
