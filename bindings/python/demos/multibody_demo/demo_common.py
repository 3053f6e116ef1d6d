"""Shared pieces of the multibody demos: the step loop and the command line."""

import argparse

import numpy as np

import novaphy


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

    def step(self):
        self.pipeline.collide(self.state, self.contacts)
        self.solver.step(self.state, self.state, self.control, self.contacts, self.dt)

    def refresh(self):
        """Recomputes body poses after joint_q / joint_qd were written from Python."""
        novaphy.eval_fk(self.model, self.state)


def rotation_z(angle):
    """Quaternion [x, y, z, w] of a rotation by angle about +Z."""
    return np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])


def arguments(description, steps):
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--steps", type=int, default=steps, help="number of steps to simulate")
    return parser.parse_args()
