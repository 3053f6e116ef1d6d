"""NovaPhy beside today's MuJoCo (PyPI) and MuJoCo 2.2.2 on the same MJCF, worlds and threads, in one run.

Each engine steps `--worlds` copies of the scene from its first keyframe (qpos0 without one), commands held,
at the file's timestep, with collision, on all threads, for `--seconds` of simulated time; `--rounds` rounds
alternate the engines and the table gives medians of robot-steps/s (worlds x steps / wall seconds):
- NovaPhy float64 and float32: novaphy.from_mujoco(today's compiled model), CollisionPipeline(margin=0: contacts
  where MuJoCo makes them, at the geoms' own margins).collide + SolverFeatherstone.step from Python;
- today's MuJoCo: one MjData per world, mj_step over them in a pool of one thread a core (mj_step releases the
  GIL; as fast here as mujoco.rollout, measured side by side);
- MuJoCo 2.2.2: novaphy_showcase's own MuJoCo loop (one mjData per world in an OpenMP loop), on the same file.
What differs: each MuJoCo uses its own solver (today's: Newton, 2.2.2: its default) with the file's iterations and
tolerance, NovaPhy its PGS with its defaults (at most 20 sweeps, stopping at pgs_tolerance 3e-5 m/s); margins,
solref/solimp, condim and timestep are the file's in all three.

    PYTHONPATH=build/python build/venv/bin/python bench/todays_mujoco.py [--worlds 1024] [--seconds 1] \
        [--rounds 3] [--out bench/results/todays_mujoco.md] [scene.xml ...]
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ThreadPoolExecutor

import mujoco

import novaphy

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
GO1 = os.path.join(ROOT, "..", "shared", "robots", "unitree_go1", "scene.xml")
SCENES = [
    os.path.join(ROOT, "bench", "scenes", "quadruped.xml"),
    os.path.join(ROOT, "bench", "scenes", "chain15.xml"),
    "/usr/share/mujoco/model/humanoid/humanoid.xml",
    GO1,
]


def novaphy_rate(m, worlds, steps, precision):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = novaphy.from_mujoco(m, worlds, precision)
    key = model.keyframes[0] if model.keyframes else None
    state, control = model.state(keyframe=key), model.control(keyframe=key)
    solver = novaphy.solvers.SolverFeatherstone(model)
    pipeline = novaphy.CollisionPipeline(model, margin=0)  # as novaphy_showcase: the geoms' own margins only
    contacts = pipeline.contacts()
    start = time.perf_counter()
    for _ in range(steps):
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, m.opt.timestep)
    return worlds * steps / (time.perf_counter() - start)


def todays_mujoco_rate(m, worlds, steps, threads):
    datas = [mujoco.MjData(m) for _ in range(worlds)]
    for d in datas:
        if m.nkey > 0:
            mujoco.mj_resetDataKeyframe(m, d, 0)

    def work(k):
        for d in datas[k::threads]:
            mujoco.mj_step(m, d, steps)

    with ThreadPoolExecutor(threads) as pool:
        start = time.perf_counter()
        list(pool.map(work, range(threads)))
        return worlds * steps / (time.perf_counter() - start)


def mujoco_222_rate(path, worlds, seconds, showcase):
    picture = os.path.join(tempfile.gettempdir(), "todays_mujoco_showcase.png")
    out = subprocess.run(
        [showcase, path, "--worlds", str(worlds), "--mujoco-worlds", str(worlds), "--seconds", str(seconds), "--kick", "0",
         "--states", "1", "--frames", "2", "--no-progress", "--picture", picture],
        capture_output=True, text=True, check=True).stdout
    return float(re.search(r"^MuJoCo 2\.2\.2\s+\d+\s+[\d.]+\s+([\d,]+)", out, re.M).group(1).replace(",", ""))


def label(path):
    """A scene's name: its file's, or its folder's for a Menagerie scene.xml"""
    name = os.path.basename(path)
    return os.path.basename(os.path.dirname(os.path.abspath(path))) if name == "scene.xml" else name


def measure(path, args, threads):
    m = mujoco.MjModel.from_xml_path(path)
    steps = round(args.seconds / m.opt.timestep)
    engines = {
        "NovaPhy float64": lambda: novaphy_rate(m, args.worlds, steps, novaphy.Precision.Float64),
        "NovaPhy float32": lambda: novaphy_rate(m, args.worlds, steps, novaphy.Precision.Float32),
        f"MuJoCo {mujoco.__version__}": lambda: todays_mujoco_rate(m, args.worlds, steps, threads),
        "MuJoCo 2.2.2": lambda: mujoco_222_rate(path, args.worlds, args.seconds, args.showcase),
    }
    rates = {name: [] for name in engines}
    for _ in range(args.rounds):
        for name, run in engines.items():
            rates[name].append(run())
    return {name: statistics.median(r) for name, r in rates.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=[s for s in SCENES if os.path.exists(s)])
    parser.add_argument("--worlds", type=int, default=1024)
    parser.add_argument("--seconds", type=float, default=1.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--showcase", default=os.path.join(ROOT, "build", "tools", "novaphy_showcase"))
    parser.add_argument("--out", help="also write the table (markdown) here")
    args = parser.parse_args()
    threads = os.cpu_count()
    today = f"MuJoCo {mujoco.__version__}"
    lines = [
        f"| scene | NovaPhy float64 | NovaPhy float32 | {today} | MuJoCo 2.2.2 | float32 / {today} | float32 / 2.2.2 |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for path in args.scenes:
        r = measure(path, args, threads)
        f32 = r["NovaPhy float32"]
        lines.append(
            f"| {label(path)} | "
            f"{r['NovaPhy float64']:,.0f} | {f32:,.0f} | {r[today]:,.0f} | {r['MuJoCo 2.2.2']:,.0f} | "
            f"{f32 / r[today]:.1f}x | {f32 / r['MuJoCo 2.2.2']:.1f}x |")
        print(lines[-1], flush=True)
    header = (f"{args.worlds} worlds, {args.seconds:g} s simulated, {threads} threads, medians of {args.rounds} "
              f"alternating rounds, robot-steps/s. Command: `{' '.join(sys.argv)}`")
    if args.out:
        with open(args.out, "w") as f:
            f.write("# NovaPhy beside today's MuJoCo and MuJoCo 2.2.2\n\n" + header + "\n\n" + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
