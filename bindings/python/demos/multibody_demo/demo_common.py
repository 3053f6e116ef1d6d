"""Shared pieces of the multibody demos: the step loop, recording, progress and the command line."""

import argparse

import numpy as np
from tqdm import tqdm

import novaphy
import novaphy.viewer


class Simulation:
    """A model with its collision pipeline, contacts, Featherstone solver, state and control."""

    def __init__(self, model, dt=1.0 / 120.0, **solver_kwargs):
        self.model = model
        self.dt = dt
        self.solver = novaphy.solvers.SolverFeatherstone(model, **solver_kwargs)
        self.pipeline = novaphy.CollisionPipeline(model)
        self.contacts = self.pipeline.contacts()
        self.state = model.state()
        self.control = model.control()
        self.recorder = None

    def step(self):
        self.pipeline.collide(self.state, self.contacts)
        self.solver.step(self.state, self.state, self.control, self.contacts, self.dt)
        if self.recorder is not None:
            self.recorder.record(self.state)

    def refresh(self):
        """Recomputes body poses after joint_q / joint_qd were written from Python."""
        novaphy.eval_fk(self.model, self.state)

    def record(self, steps, frames=60):
        """Records about `frames` frames over the next `steps` steps."""
        self.recorder = novaphy.viewer.Recorder(self.model, every=max(1, steps // frames))
        self.recorder.record(self.state)


def steps_of(count, description):
    """range(count) with a progress bar on a terminal."""
    return tqdm(range(count), desc=description, disable=None, leave=False)


def rotation_z(angle):
    """Quaternion [x, y, z, w] of a rotation by angle about +Z."""
    return np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])


def arguments(description, steps):
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--steps", type=int, default=steps, help="number of steps to simulate")
    parser.add_argument("--render", metavar="OUT.gif", help="write an animated GIF of the run")
    return parser.parse_args()


def save_render(sim, path):
    if path:
        sim.recorder.save_gif(path)
        print(f"wrote {path} ({len(sim.recorder.frames)} frames)")
