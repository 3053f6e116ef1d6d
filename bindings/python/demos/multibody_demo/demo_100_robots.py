"""100 robots: a 10 x 10 grid of floating-base quadrupeds (sprung legs) dropped onto the ground.

Each robot is bench/scenes/quadruped.xml imported through MuJoCo's parser at its place in the grid.
"""

import os

import numpy as np

import novaphy
from demo_common import Simulation, arguments

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "bench", "scenes", "quadruped.xml")
SPACING = 1.5


def build(side=10):
    builder = novaphy.ModelBuilder()
    torsos = []
    for i in range(side * side):
        x, y = SPACING * (i % side), SPACING * (i // side)
        first_body = builder.body_count
        builder.add_mjcf(SCENE, xform=novaphy.Transform([x, y, 0.0]), static_shapes=(i == 0))
        torsos.append(first_body)  # the torso is each file's first body
    return Simulation(builder.finalize(), dt=0.005), torsos


def upright(sim, torsos):
    """Height of each torso and the z component of its up axis."""
    q = sim.state.body_q[torsos]
    x, y, z, w = q[:, 3], q[:, 4], q[:, 5], q[:, 6]
    up_z = 1 - 2 * (x * x + y * y)
    return q[:, 2], up_z


def run(steps, side=10):
    sim, torsos = build(side)
    for _ in range(steps):
        sim.step()
    height, up_z = upright(sim, torsos)
    return {
        "robots": len(torsos),
        "upright": int(np.sum((height > 0.3) & (up_z > 0.9))),
        "min_height": float(height.min()),
        "contacts": sim.contacts.contact_count,
    }


def main():
    args = arguments(__doc__.splitlines()[0], steps=400)
    s = run(args.steps)
    print(
        f"{s['upright']} of {s['robots']} robots standing (lowest torso {s['min_height']:.3f} m), "
        f"{s['contacts']} contacts"
    )


if __name__ == "__main__":
    main()
