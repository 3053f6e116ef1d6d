"""Wrecking ball: a heavy ball on a hinged chain swings down from horizontal into a tower of boxes."""

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of, rotation_z

LINKS = 6
LINK_LENGTH = 0.5
PIVOT = np.array([0.0, 3.6, 0.0])
BALL_RADIUS = 0.3
BOX = 0.15  # half extent
TOWER = (2, 6)  # columns, rows


def build(*, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0, mu=0.6)
    along_x = novaphy.Transform([LINK_LENGTH / 2, 0.0, 0.0], rotation_z(np.pi / 2))
    parent = -1
    for i in range(LINKS):
        body = novaphy.RigidBody.from_capsule(0.5, 0.03, LINK_LENGTH / 2 - 0.03)
        body.inertia = np.diag(body.inertia.diagonal()[[1, 0, 2]])
        body.com = np.array([LINK_LENGTH / 2, 0.0, 0.0])
        link = builder.add_body(body)
        builder.add_shape_capsule(link, 0.03, LINK_LENGTH / 2 - 0.03, xform=along_x)
        # the chain hangs towards -x at first, released from horizontal
        offset = PIVOT if i == 0 else np.array([LINK_LENGTH, 0.0, 0.0])
        rotation = rotation_z(np.pi) if i == 0 else rotation_z(0.0)
        builder.add_joint_revolute(parent, link, parent_xform=novaphy.Transform(offset, rotation), axis=[0, 0, 1])
        parent = link
    ball = builder.add_body(novaphy.RigidBody.from_sphere(40.0, BALL_RADIUS))
    builder.add_shape_sphere(ball, BALL_RADIUS, mu=0.4)
    builder.add_joint_fixed(parent, ball, parent_xform=novaphy.Transform([LINK_LENGTH + BALL_RADIUS, 0.0, 0.0]))
    boxes = []
    for column in range(TOWER[0]):
        for row in range(TOWER[1]):
            position = [0.35 + 2 * BOX * column, BOX + 2 * BOX * row, 0.0]
            box = builder.add_body(novaphy.RigidBody.from_box(1.0, [BOX] * 3), xform=novaphy.Transform(position))
            builder.add_shape_box(box, [BOX] * 3, mu=0.6)
            boxes.append(box)
    sim = Simulation(builder.finalize(), dt=1.0 / 240.0, solver=solver)
    return sim, boxes


def run(steps, *, render=None, frames=60, solver="featherstone"):
    sim, boxes = build(solver=solver)
    if render:
        sim.record(steps, frames)
    start = sim.state.body_q[boxes, :3].copy()
    for _ in steps_of(steps, "wrecking_ball"):
        sim.step()
    moved = np.linalg.norm(sim.state.body_q[boxes, :3] - start, axis=1)
    save_render(sim, render)
    return {
        "boxes": len(boxes),
        "boxes_moved": int(np.sum(moved > 0.3)),
        "tower_height_before": float(start[:, 1].max() + BOX),
        "tower_height_after": float(sim.state.body_q[boxes, 1].max() + BOX),
    }


def main():
    args = arguments(__doc__.splitlines()[0], steps=720)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"{s['boxes_moved']} of {s['boxes']} boxes knocked more than 0.3 m; the tower went from "
        f"{s['tower_height_before']:.2f} m to {s['tower_height_after']:.2f} m high"
    )


if __name__ == "__main__":
    main()
