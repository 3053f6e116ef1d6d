"""100 robots: a 10 x 10 grid of floating-base quadrupeds (sprung legs) dropped onto the ground.

Each robot is bench/scenes/quadruped.xml imported through MuJoCo's parser at its place in the grid,
0.3 m above its standing height, without the file's own floor. --solver semi_implicit and xpbd refuse it: the
importer makes each hip (a body with two hinges) a chain whose first link is massless, and they need every moving
body to have a mass.
"""

import os

import numpy as np

import novaphy
from demo_common import Simulation, arguments, save_render, steps_of

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "bench", "scenes", "quadruped.xml")
SPACING = 1.5
DROP = 0.3  # metres above standing height


def build(*, side=10, solver="featherstone"):
    builder = novaphy.ModelBuilder()
    builder.add_plane([0.0, 0.0, 1.0], 0.0, mu=1.0)  # the robots' MJCF is +Z up
    torsos = []
    for i in range(side * side):
        x, y = SPACING * (i % side), SPACING * (i // side)
        first_body = builder.body_count
        builder.add_mjcf(SCENE, xform=novaphy.Transform([x, y, DROP]), static_shapes=False)
        torsos.append(first_body)  # the torso is each file's first body
    return Simulation(builder.finalize(), dt=0.005, solver=solver), torsos


def upright(sim, torsos):
    """Height of each torso and the z component of its up axis."""
    q = sim.state.body_q[torsos]
    x, y, z, w = q[:, 3], q[:, 4], q[:, 5], q[:, 6]
    up_z = 1 - 2 * (x * x + y * y)
    return q[:, 2], up_z


def run(steps, *, side=10, render=None, frames=60, solver="featherstone"):
    sim, torsos = build(side=side, solver=solver)
    if render:
        sim.record(steps, frames)
    for _ in steps_of(steps, "100_robots"):
        sim.step()
    height, up_z = upright(sim, torsos)
    save_render(sim, render)
    return {
        "robots": len(torsos),
        "upright": int(np.sum((height > 0.3) & (up_z > 0.9))),
        "min_height": float(height.min()),
        "contacts": sim.contacts.contact_count,
    }


def main():
    args = arguments(__doc__.splitlines()[0], steps=400)
    s = run(args.steps, render=args.render, solver=args.solver)
    print(
        f"{s['upright']} of {s['robots']} robots standing (lowest torso {s['min_height']:.3f} m), "
        f"{s['contacts']} contacts"
    )


if __name__ == "__main__":
    main()
