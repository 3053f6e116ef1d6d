"""Newton's cradle: five steel balls on hinges; the first is raised and released.

Elastic contacts (restitution 1) pass the momentum along the row: the first ball stops and the last
swings out to the height the first was released from.
"""

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of

BALLS = 5
RADIUS = 0.1
LENGTH = 1.0
GAP = 0.004  # a hair between the balls, so the impacts run down the row one after another
RELEASE = np.radians(30.0)
DT = 1.0 / 1000.0


def build(*, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    for i in range(BALLS):
        x = i * (2 * RADIUS + GAP)
        ball = builder.add_body(novaphy.RigidBody.from_sphere(1.0, RADIUS))
        builder.add_shape_sphere(ball, RADIUS, mu=0.0, restitution=1.0)
        builder.add_joint_revolute(
            -1,
            ball,
            parent_xform=novaphy.Transform([x, 2.0, 0.0]),
            child_xform=novaphy.Transform([0.0, LENGTH, 0.0]),
            axis=[0.0, 0.0, 1.0],
        )
    # XPBD bounces only with enable_restitution; it has no restitution threshold
    sim = Simulation(builder.finalize(), dt=DT, solver=solver, angular_damping=0.0, enable_restitution=True)
    sim.set_setting("restitution_threshold", 0.01)
    sim.state.joint_q[0] = -RELEASE  # swing the first ball out to -x
    sim.refresh()
    return sim


def run(steps, *, render=None, frames=60, solver="featherstone"):
    """Simulates until the last ball turns back (or steps run out) and reports the swing."""
    sim = build(solver=solver)
    if render:
        sim.record(steps, frames)
    peak_last = 0.0
    first_after = 0.0
    hit = False
    for _ in steps_of(steps, "newtons_cradle_pendulum"):
        sim.step()
        q, qd = sim.state.joint_q, sim.state.joint_qd
        hit = hit or q[0] >= -1e-3
        if hit:
            peak_last = max(peak_last, q[-1])
            first_after = max(first_after, abs(q[0]))
            if q[-1] > 0.01 and qd[-1] < 0:
                break
    save_render(sim, render)
    return {"release_angle": RELEASE, "last_ball_peak_angle": peak_last, "first_ball_peak_after_impact": first_after}


def main():
    args = arguments(__doc__.splitlines()[0], steps=2000)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"released the first ball at {np.degrees(s['release_angle']):.1f} deg; the last ball swung out to "
        f"{np.degrees(s['last_ball_peak_angle']):.1f} deg while the first stayed within "
        f"{np.degrees(s['first_ball_peak_after_impact']):.1f} deg"
    )


if __name__ == "__main__":
    main()
