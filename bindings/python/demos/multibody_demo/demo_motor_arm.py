"""Motor arm: a torque-level PD controller swings an arm a quarter turn, sweeping boxes aside.

The PD torque is computed in Python from the state each step and written into control.joint_f.
"""

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of

ARM = np.array([0.6, 0.05, 0.05])  # half extents; the arm turns about the vertical axis at its end
TARGET = np.pi / 2
KP, KD = 400.0, 60.0


def build(*, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0, mu=0.5)
    arm = builder.add_body(novaphy.RigidBody.from_box(4.0, ARM))
    builder.add_shape_box(arm, ARM, mu=0.3)
    builder.add_joint_revolute(
        -1,
        arm,
        parent_xform=novaphy.Transform([0.0, 0.12, 0.0]),
        child_xform=novaphy.Transform([-ARM[0], 0.0, 0.0]),
        axis=[0, 1, 0],
    )
    boxes = []
    for radius, angle in [(0.6, 0.5), (0.9, 0.8), (0.75, 1.1)]:
        # boxes on the ground in the arm's sweep (rotation about +Y takes +x towards -z)
        position = [radius * np.cos(angle), 0.08, -radius * np.sin(angle)]
        box = builder.add_body(novaphy.RigidBody.from_box(0.3, [0.08] * 3), xform=novaphy.Transform(position))
        builder.add_shape_box(box, [0.08] * 3, mu=0.5)
        boxes.append(box)
    return Simulation(builder.finalize(), solver=solver), boxes


def run(steps, *, render=None, frames=60, solver="featherstone"):
    sim, boxes = build(solver=solver)
    if render:
        sim.record(steps, frames)
    start = sim.state.body_q[boxes, :3].copy()
    for _ in steps_of(steps, "motor_arm"):
        q, qd = sim.state.joint_q[0], sim.state.joint_qd[0]
        sim.control.joint_f[0] = KP * (TARGET - q) - KD * qd
        sim.step()
    moved = np.linalg.norm(sim.state.body_q[boxes, :3] - start, axis=1)
    save_render(sim, render)
    return {"arm_angle": float(sim.state.joint_q[0]), "target": TARGET, "boxes_moved": int(np.sum(moved > 0.05))}


def main():
    args = arguments(__doc__.splitlines()[0], steps=600)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"arm at {np.degrees(s['arm_angle']):.2f} deg for a target of {np.degrees(s['target']):.0f} deg; "
        f"{s['boxes_moved']} of 3 boxes swept aside"
    )


if __name__ == "__main__":
    main()
