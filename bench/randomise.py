"""Randomising every per-world parameter (Model.set_parameter) of 4096 Go1 worlds beside one step of them: the
set_parameter calls that write new values (made beforehand with numpy) into every world, the first collide and step
after them (the step reads what depends on them again), one before them and one two steps after, float32 and
float64, one thread (pinned to CPU 0) and two; medians of `reps`.
    build/venv/bin/python bench/randomise.py [--worlds 4096] [--reps 7] > bench/results/randomise.md"""
import argparse
import os
import subprocess
import sys

ROBOT = "../shared/robots/unitree_go1/scene.xml"

RUN = r"""
import statistics, sys, time
import numpy as np
import novaphy
from replicated import replicated
robot_file, precision, threads, worlds, reps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
model, state, control, solver, pipeline, contacts = replicated(robot_file, precision, threads, worlds)
rng = np.random.default_rng(0)
shape_world = np.asarray(model.shape_world)
original = {name: np.array(getattr(model, name)) for name in novaphy.Model.parameter_names}

def per_world(name):
    x = original[name]
    if name.startswith("shape_"):
        x = x[shape_world >= 0]
    return x.reshape((worlds, -1) + x.shape[1:])

def values():
    # every parameter of every world: factors around 1 (inertia by its body's mass factor), offsets for the centres
    # of mass, the ranges and priorities as they are
    mass = rng.uniform(0.8, 1.2, per_world("body_mass").shape)
    out = {}
    for name in novaphy.Model.parameter_names:
        x = per_world(name)
        if name == "body_mass":
            x = x * mass
        elif name == "body_inertia":
            x = x * mass[..., None]
        elif name == "body_com":
            x = x + rng.uniform(-0.01, 0.01, x.shape)
        elif name in ("actuator_gain", "actuator_bias", "joint_damping", "joint_armature", "joint_frictionloss",
                      "joint_stiffness", "shape_mu", "world_gravity"):
            x = x * rng.uniform(0.8, 1.2, x.shape)
        out[name] = np.ascontiguousarray(x)
    return out

def step():
    pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, 0.002)

for _ in range(20):
    step()
plain, written, first, later = [], [], [], []
for _ in range(reps):
    start = time.perf_counter()
    step()
    plain.append(time.perf_counter() - start)
    given = values()
    start = time.perf_counter()
    for name, x in given.items():
        model.set_parameter(name, x)
    written.append(time.perf_counter() - start)
    start = time.perf_counter()
    step()
    first.append(time.perf_counter() - start)
    step()
    start = time.perf_counter()
    step()
    later.append(time.perf_counter() - start)
print(statistics.median(plain), statistics.median(written), statistics.median(first), statistics.median(later))
"""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--worlds", type=int, default=4096)
    parser.add_argument("--reps", type=int, default=7)
    args = parser.parse_args()
    build = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "python")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([build, os.path.dirname(os.path.abspath(__file__))]),
               OMP_WAIT_POLICY="passive")
    print(f"{args.worlds} worlds of {ROBOT}, collide + step at dt 0.002; medians of {args.reps}\n")
    print("| precision | threads | collide + step ms | set_parameter of every field, every world ms | "
          "collide + the first step after ms | (set_parameter + first step's extra) / step | collide + a later step "
          "ms |")
    print("|---|---|---|---|---|---|---|")
    for precision in ("Float32", "Float64"):
        for threads in (1, 2):
            pin = ["taskset", "-c", "0"] if threads == 1 else []
            done = subprocess.run(pin + [sys.executable, "-c", RUN, ROBOT, precision, str(threads), str(args.worlds),
                                         str(args.reps)], env=env, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(done.stderr)
            plain, written, first, later = map(float, done.stdout.split())
            print(f"| {precision} | {threads} | {1e3 * plain:.2f} | {1e3 * written:.2f} | {1e3 * first:.2f} | "
                  f"{(written + first - plain) / plain:.2f} | {1e3 * later:.2f} |", flush=True)


if __name__ == "__main__":
    main()
