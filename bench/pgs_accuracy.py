"""How far a step's velocities land from the converged contact solve, under the PGS settings a user can pick.

Along one trajectory of a scene (8 worlds from its first keyframe, joint velocities kicked by `--kick` times a
standard normal draw, stepped with the default settings at the file's timestep), every solver below steps from
the same state each step (keeping its own warm starts) and the joint velocities it reaches are compared with
those of a reference that sweeps to a fixed point (5000 sweeps at most). Prints the median, 90th percentile
and largest difference over the steps after `--skip` (the landing), in m/s and rad/s, and each solver's mean
microseconds a step (8 worlds, from Python: a rough guide; bench/ and tools/novaphy_showcase time the step).

    PYTHONPATH=build/python build/venv/bin/python bench/pgs_accuracy.py scene.xml [--kick 0] [--steps 500]
        [--skip 100] [--float32]
"""

import argparse
import sys
import time

import numpy as np

import novaphy


def build(path, worlds, precision):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(path)
    batch = novaphy.ModelBuilder(gravity=robot.gravity)
    batch.precision = precision
    batch.replicate(robot, worlds)
    return batch.finalize()


def solver(model, **settings):
    s = novaphy.solvers.SolverFeatherstone(model)
    for name, value in settings.items():
        setattr(s.settings, name, value)
    return s


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--kick", type=float, default=0)
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--skip", type=int, default=100)
    parser.add_argument("--float32", action="store_true")
    parser.add_argument("--dt", type=float, default=0.002)
    o = parser.parse_args()
    precision = novaphy.Precision.Float32 if o.float32 else novaphy.Precision.Float64
    model = build(o.scene, 8, precision)
    key = model.keyframes[0] if model.keyframes else None
    state, control = model.state(keyframe=key), model.control(keyframe=key)
    qd = np.asarray(state.joint_qd)
    qd += o.kick * np.random.default_rng(1).standard_normal(qd.shape)
    solvers = {
        "converged (reference)": solver(model, num_iterations=5000, pgs_tolerance=0),
        "defaults": solver(model),
        "pgs_tolerance 0": solver(model, pgs_tolerance=0),
        "pgs_tolerance 1e-3": solver(model, pgs_tolerance=1e-3),
        "warmstarting_factor 1": solver(model, warmstarting_factor=1),
    }
    pipeline = novaphy.CollisionPipeline(model, margin=0)
    contacts = pipeline.contacts()
    out = model.state()
    reached = {name: [] for name in solvers}
    seconds = dict.fromkeys(solvers, 0.0)
    for _ in range(o.steps):
        pipeline.collide(state, contacts)
        for name, s in solvers.items():
            if name == "defaults":
                continue
            start = time.perf_counter()
            s.step(state, out, control, contacts, o.dt)
            seconds[name] += time.perf_counter() - start
            reached[name].append(np.array(out.joint_qd))
        start = time.perf_counter()
        solvers["defaults"].step(state, state, control, contacts, o.dt)  # the trajectory
        seconds["defaults"] += time.perf_counter() - start
        reached["defaults"].append(np.array(state.joint_qd))
    reference = np.array(reached["converged (reference)"])
    print(f"{o.scene}, kick {o.kick}, {'float32' if o.float32 else 'float64'}, steps {o.skip}-{o.steps}")
    print("| solver | median | 90th percentile | largest | us a step |")
    print("|---|---:|---:|---:|---:|")
    for name in solvers:
        e = np.abs(np.array(reached[name]) - reference).max(axis=-1)[o.skip :]
        print(f"| {name} | {np.median(e):.2e} | {np.percentile(e, 90):.2e} | {e.max():.2e} | "
              f"{seconds[name] * 1e6 / o.steps:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
