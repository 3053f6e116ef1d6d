"""Rope: a 15-link hinged chain released from horizontal swings down under gravity.

Reduced coordinates keep every link attached exactly, however hard the chain whips; the maximal-coordinate solvers
hold the links together by constraints, which give a little as the tip whips.
"""

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of, rotation_z

LINKS = 15
LINK_LENGTH = 0.1
RADIUS = 0.015
PIVOT = np.array([0.0, 2.0, 0.0])
DT = 1.0 / 240.0  # the whipping tip reaches ~200 rad/s; 1/120 s is too coarse for it


def build(*, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    along_x = novaphy.Transform([LINK_LENGTH / 2, 0.0, 0.0], rotation_z(np.pi / 2))  # capsule axis Y -> X
    parent = -1
    for i in range(LINKS):
        body = novaphy.RigidBody.from_capsule(0.1, RADIUS, LINK_LENGTH / 2 - RADIUS)
        body.inertia = np.diag(body.inertia.diagonal()[[1, 0, 2]])  # the capsule runs along X
        body.com = np.array([LINK_LENGTH / 2, 0.0, 0.0])
        link = builder.add_body(body)
        builder.add_shape_capsule(link, RADIUS, LINK_LENGTH / 2 - RADIUS, xform=along_x)
        offset = PIVOT if i == 0 else np.array([LINK_LENGTH, 0.0, 0.0])
        builder.add_joint_revolute(parent, link, parent_xform=novaphy.Transform(offset), axis=[0, 0, 1], damping=0.002)
        parent = link
    sim = Simulation(builder.finalize(), dt=DT, solver=solver)
    # SemiImplicit: two position passes a step keep the whipping links joined within millimetres (without, its rows'
    # erp lets them open by 2 cm: docs/solvers.md)
    sim.set_setting("position_iterations", 2)
    return sim


def link_end(pose):
    """World position of the far end of a link (its +X axis, LINK_LENGTH from its origin) at pose [p, q]."""
    x, y, z, w = pose[3:]
    return pose[:3] + LINK_LENGTH * np.array([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])


def tip(sim):
    """World position of the free end of the last link."""
    return link_end(sim.state.body_q[-1])


def run(steps, *, render=None, frames=60, solver="featherstone"):
    sim = build(solver=solver)
    if render:
        sim.record(steps, frames)
    lowest_tip = np.inf
    worst_joint_gap = 0.0
    for _ in steps_of(steps, "rope"):
        sim.step()
        lowest_tip = min(lowest_tip, tip(sim)[1])
        # each link's origin sits at the end of its parent
        q = sim.state.body_q
        for i in range(1, LINKS):
            worst_joint_gap = max(worst_joint_gap, np.linalg.norm(link_end(q[i - 1]) - q[i, :3]))
    save_render(sim, render)
    return {"lowest_tip_height": lowest_tip, "worst_joint_gap": worst_joint_gap, "final_tip": tip(sim)}


def main():
    args = arguments(__doc__.splitlines()[0], steps=1200)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"chain of {LINKS} links from y = {PIVOT[1]:.1f} m: the tip swung down to y = {s['lowest_tip_height']:.3f} m; "
        f"links stayed attached within {s['worst_joint_gap']:.1e} m"
    )


if __name__ == "__main__":
    main()
