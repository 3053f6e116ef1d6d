"""Seesaw: a box dropped onto one end of a plank on a revolute fulcrum tips it over to that side."""

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of

FULCRUM = np.array([0.0, 0.5, 0.0])
PLANK = np.array([1.0, 0.04, 0.25])  # half extents
LIMIT = 0.4  # rad


def build(*, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    plank = builder.add_body(novaphy.RigidBody.from_box(2.0, PLANK))
    builder.add_shape_box(plank, PLANK, mu=0.8)
    builder.add_joint_revolute(
        -1, plank, parent_xform=novaphy.Transform(FULCRUM), axis=[0, 0, 1], limit_lower=-LIMIT, limit_upper=LIMIT
    )
    box = builder.add_body(novaphy.RigidBody.from_box(3.0, [0.15] * 3), xform=novaphy.Transform([0.7, 2.0, 0.0]))
    builder.add_shape_box(box, [0.15] * 3, mu=0.8)
    return Simulation(builder.finalize(), solver=solver), box


def run(steps, *, render=None, frames=60, solver="featherstone"):
    sim, box = build(solver=solver)
    if render:
        sim.record(steps, frames)
    for _ in steps_of(steps, "seesaw"):
        sim.step()
    save_render(sim, render)
    return {"plank_angle": float(sim.state.joint_q[0]), "box_height": float(sim.state.body_q[box, 1])}


def main():
    args = arguments(__doc__.splitlines()[0], steps=360)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"the plank tilted to {np.degrees(s['plank_angle']):.1f} deg (limit {np.degrees(LIMIT):.0f}); "
        f"the box rests at y = {s['box_height']:.2f} m"
    )


if __name__ == "__main__":
    main()
