"""Shared pieces of the multibody demos: the step loop, recording, progress and the command line."""

import argparse
import re

import numpy as np
from tqdm import tqdm

import novaphy
import novaphy.viewer


# the solvers --solver picks: reduced coordinates (Featherstone) or maximal coordinates (the other two)
SOLVERS = {
    "featherstone": novaphy.solvers.SolverFeatherstone,
    "semi_implicit": novaphy.solvers.SolverSemiImplicit,
    "xpbd": novaphy.solvers.SolverXPBD,
}


def _keywords(solver_class):
    """The keyword arguments a solver's constructor takes: the parameters with a default in its signature line."""
    signature = solver_class.__init__.__doc__.splitlines()[0]
    return set(re.findall(r"(\w+): [^,=]+ =", signature))


def _settings(solver_class):
    """The names of a solver's settings (solver.settings.<name>)."""
    return {field["name"] for field in getattr(novaphy.solvers, solver_class.__name__ + "Settings").fields()}


KEYWORDS = {name: _keywords(solver_class) for name, solver_class in SOLVERS.items()}
SETTINGS = {name: _settings(solver_class) for name, solver_class in SOLVERS.items()}


def _check_known(names, per_solver, what):
    """Raises on a name no solver knows (a typo), since each solver skips the names it lacks."""
    unknown = set(names) - set().union(*per_solver.values())
    if unknown:
        raise TypeError(f"no solver has the {what} {', '.join(sorted(unknown))}")


class Simulation:
    """A model with its collision pipeline, contacts, solver (one of SOLVERS), state and control."""

    def __init__(self, model, *, dt=1.0 / 120.0, solver="featherstone", **solver_kwargs):
        # a demo tunes its scene for every solver at once: each solver takes the keyword arguments it has
        _check_known(solver_kwargs, KEYWORDS, "keyword argument")
        self.model = model
        self.dt = dt
        self.solver_name = solver
        accepted = {k: v for k, v in solver_kwargs.items() if k in KEYWORDS[solver]}
        self.solver = SOLVERS[solver](model, **accepted)
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

    def set_setting(self, name, value):
        """Sets solver.settings.<name> where the chosen solver has that setting; skips it elsewhere."""
        _check_known([name], SETTINGS, "setting")
        if name in SETTINGS[self.solver_name]:
            setattr(self.solver.settings, name, value)

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
    parser.add_argument("--solver", choices=list(SOLVERS), default="featherstone", help="the solver to step with")
    return parser.parse_args()


def save_render(sim, path):
    if path:
        sim.recorder.save_gif(path)
        print(f"wrote {path} ({len(sim.recorder.frames)} frames)")
