"""The speed/accuracy trade across NovaPhy's three solvers: robot-steps per second against the error to a converged
reference, for Go1 (../shared/robots), the quadruped and the 15-link chain (bench/scenes) and a rope of 20
ball-jointed segments, over each solver's knobs (dt; SolverSemiImplicit's sweeps; SolverXPBD's substeps and
iterations). Writes a markdown table and a plot:

    PYTHONPATH=build/python build/venv/bin/python bench/solver_family.py \\
        --out bench/results/solver_family.md --plot bench/results/solver_family.png

Error: the RMS over bodies of the distance between a body's position and the reference's after the scene's time
(the reference: SolverFeatherstone at a tenth of the scene's dt). Speed: `--worlds` replicas stepped together on
`--threads` threads, the median of `--repeats` timed runs of `--steps` steps after one of warm-up.
"""

import argparse
import os
import statistics
import subprocess
import time
import warnings

import numpy as np

import novaphy

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
ROBOTS = os.environ.get("MENAGERIE_ROOT", os.path.join(ROOT, "..", "shared", "robots"))


def mjcf(path):
    def build():
        robot = novaphy.ModelBuilder()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot.add_mjcf(path)
        return robot

    return build


def rope():
    """20 capsule segments on Ball joints, laid out level from a pivot (the first joint's frame turned a quarter about
    z, so the segments' -y runs along +x): it swings down."""
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(y=-3.0)
    parent, half = -1, 0.05
    turn = [0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)]
    for _ in range(20):
        body = builder.add_body(novaphy.RigidBody.from_capsule(0.1, 0.015, half))
        at = novaphy.Transform([0, -half, 0]) if parent >= 0 else novaphy.Transform([0, 0, 0], turn)
        builder.add_joint_ball(parent, body, parent_xform=at, child_xform=novaphy.Transform([0, half, 0]))
        parent = body
    return builder


# name, builder, dt, seconds simulated for the error
SCENES = [
    ("go1", mjcf(os.path.join(ROBOTS, "unitree_go1", "scene.xml")), 0.002, 1.0),
    ("quadruped", mjcf(os.path.join(ROOT, "bench", "scenes", "quadruped.xml")), 0.005, 1.0),
    ("chain15", mjcf(os.path.join(ROOT, "bench", "scenes", "chain15.xml")), 0.002, 0.5),
    ("rope", rope, 0.002, 0.5),
]


def configurations(dt):
    """(solver, label, dt, constructor) for each point of the sweep."""
    S = novaphy.solvers
    out = []
    for scale in (1, 2):
        out.append(("featherstone", f"dt/{scale}", dt / scale, lambda m: S.SolverFeatherstone(m)))

    def hard_rows(m):  # (an imported model's limits, dry friction and equalities as hard rows)
        solver = S.SolverFeatherstone(m)
        solver.settings.soft_constraints = False
        return solver

    out.append(("featherstone", "dt/1, hard rows", dt, hard_rows))
    for scale in (1, 2):
        for sweeps in (10, 20, 50):
            out.append(("semi_implicit", f"dt/{scale}, {sweeps} sweeps", dt / scale,
                        lambda m, n=sweeps: S.SolverSemiImplicit(m, num_iterations=n)))
    for substeps in (4, 8, 16):
        for iterations in (1, 2, 4):
            out.append(("xpbd", f"{substeps} substeps, {iterations} iterations", dt,
                        lambda m, s=substeps, i=iterations: S.SolverXPBD(m, substeps=s, iterations=i)))
    return out


def start(model):
    key = model.keyframes[0] if model.keyframes else None
    return (model.state(keyframe=key), model.control(keyframe=key)) if key else (model.state(), model.control())


def final_positions(model, solver, dt, seconds):
    state, control = start(model)
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    for _ in range(int(round(seconds / dt))):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, dt)
    return np.array(state.body_q)[:, :3]


def robot_steps_per_second(model, solver, dt, worlds, steps, repeats, threads):
    solver.settings.num_threads = threads
    state, control = start(model)
    pipeline = novaphy.CollisionPipeline(model, num_threads=threads)
    contacts = pipeline.contacts()
    times = []
    for repeat in range(repeats + 1):
        t0 = time.perf_counter()
        for _ in range(steps):
            pipeline.collide(state, contacts)
            solver.step(state, state, control, contacts, dt)
        if repeat:  # (the first run warms up)
            times.append(time.perf_counter() - t0)
    return worlds * steps / statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", type=int, default=64)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default="bench/results/solver_family.md")
    parser.add_argument("--plot", default="bench/results/solver_family.png")
    args = parser.parse_args()
    rows = []
    for name, build, dt, seconds in SCENES:
        one = build().finalize()
        many_builder = novaphy.ModelBuilder()
        many_builder.replicate(build(), args.worlds, spacing=[3.0, 0.0, 0.0])
        many = many_builder.finalize()
        reference = final_positions(one, novaphy.solvers.SolverFeatherstone(one), dt / 10, seconds)
        for solver_name, label, step_dt, make in configurations(dt):
            try:
                positions = final_positions(one, make(one), step_dt, seconds)
                error = float(np.sqrt(np.mean(np.sum((positions - reference) ** 2, axis=1))))
                speed = robot_steps_per_second(many, make(many), step_dt, args.worlds, args.steps, args.repeats,
                                               args.threads)
                finite = bool(np.all(np.isfinite(positions)))
            except ValueError as e:  # a model the solver does not take
                error, speed, finite = float("nan"), float("nan"), str(e).split(":")[0]
            # per simulated second: a run at dt/2 takes twice the steps
            rows.append((name, solver_name, label, speed, speed * step_dt, error, finite))
            print(rows[-1], flush=True)
    write(rows, args)


def write(rows, args):
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    lines = [
        "# The speed/accuracy trade across the three solvers",
        "",
        "Made by `PYTHONPATH=build/python build/venv/bin/python bench/solver_family.py` (bench/solver_family.py: "
        f"{args.worlds} worlds, {args.threads} threads, median of {args.repeats} runs of {args.steps} steps; "
        f"commit {commit}). Error: RMS over bodies of the position error against SolverFeatherstone at a tenth of "
        "the scene's dt, after the scene's time (Go1 and the quadruped 1 s standing at their keyframe or start, the "
        "chain and the rope 0.5 s swinging). Simulated s/s: robot-steps/s times dt (a smaller dt takes more steps).",
        "",
        "| scene | solver | setting | robot-steps/s | simulated robot-s/s | error (m) | finite |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, solver, label, speed, sim, error, finite in rows:
        lines.append(f"| {name} | {solver} | {label} | {speed:,.0f} | {sim:,.1f} | {error:.2e} | {finite} |")
    with open(args.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r[0] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(4 * len(scenes), 3.6))
    colours = {"featherstone": "tab:blue", "semi_implicit": "tab:orange", "xpbd": "tab:green"}
    for ax, scene in zip(axes, scenes):
        for solver, colour in colours.items():
            pts = [(r[4], max(r[5], 1e-12)) for r in rows if r[0] == scene and r[1] == solver and r[6] is True]
            if pts:
                ax.scatter(*zip(*pts), color=colour, label=solver, s=18)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(scene)
        ax.set_xlabel("simulated robot-seconds per second")
    axes[0].set_ylabel("position error (m)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.plot, dpi=110)


if __name__ == "__main__":
    main()
