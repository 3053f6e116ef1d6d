"""A batched step on one thread and on all, with the machine quiet and with busy processes, for one or more builds.

Each measurement is a child process (`--child`: a fresh OpenMP runtime, so that OMP_WAIT_POLICY applies) that
steps `--worlds` copies of the scene (collide + step, float32, commands held, the file's keyframe) for `--steps`
steps after `--warmup` and prints the median and mean of its step times. The rounds alternate every case, so that
a slow spell of a shared machine falls on all of them; the table gives each case's medians over the rounds.
Loaded: `--busy` processes (default: one a core) spin for the case's length and are killed after it, whatever
happens. Builds: NAME=PYTHONPATH (the default, `new=build/python`); `passive` adds the first build under
OMP_WAIT_POLICY=passive, for reference.

    PYTHONPATH=build/python build/venv/bin/python bench/threads_under_load.py \
        [--builds today=/path/to/base/python,new=build/python] [--passive] [--rounds 5] [--out FILE] [scene.xml]
"""

import argparse
import os
import signal
import statistics
import subprocess
import sys
import time
import warnings

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
GO1 = os.path.join(ROOT, "..", "shared", "robots", "unitree_go1", "scene.xml")
BUSY = "import time\nend = time.time() + {seconds}\nwhile time.time() < end: pass\n"


def child(args):
    import novaphy

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = novaphy.ModelBuilder()
        robot.add_mjcf(args.scene)
        batch = novaphy.ModelBuilder(gravity=robot.gravity)
        batch.precision = novaphy.Precision.Float32
        batch.replicate(robot, args.worlds)
        model = batch.finalize()
    key = model.keyframes[0] if model.keyframes else None
    state, control = model.state(keyframe=key), model.control(keyframe=key)
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.num_threads = args.threads
    pipeline = novaphy.CollisionPipeline(model, margin=0, num_threads=args.threads)
    contacts = pipeline.contacts()
    times = []
    for k in range(args.warmup + args.steps):
        start = time.perf_counter()
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, args.dt)
        if k >= args.warmup:
            times.append(time.perf_counter() - start)
    print(f"{1e3 * statistics.median(times):.4f} {1e3 * statistics.mean(times):.4f}")


def measure(args, path, threads, passive, busy):
    env = dict(os.environ, PYTHONPATH=path)
    env.pop("OMP_WAIT_POLICY", None)
    if passive:
        env["OMP_WAIT_POLICY"] = "passive"
    cmd = [sys.executable, os.path.abspath(__file__), "--child", "--threads", str(threads), "--worlds",
           str(args.worlds), "--steps", str(args.steps), "--warmup", str(args.warmup), "--dt", str(args.dt), args.scene]
    spinners = []
    try:
        # each busy process ends by itself after the case's longest time, and is killed when the case ends
        spinners = [subprocess.Popen([sys.executable, "-c", BUSY.format(seconds=args.case_seconds)])
                    for _ in range(busy)]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=args.case_seconds)
    finally:
        for p in spinners:
            p.kill()
            p.wait()
    if out.returncode != 0:
        sys.exit(out.stderr)
    median, mean = (float(x) for x in out.stdout.split())
    return median, mean


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", nargs="?", default=GO1)
    parser.add_argument("--child", action="store_true")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--builds", default="new=" + os.path.join(ROOT, "build", "python"))
    parser.add_argument("--passive", action="store_true")
    parser.add_argument("--busy", type=int, default=os.cpu_count())
    parser.add_argument("--worlds", type=int, default=1024)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--warmup", type=int, default=50)
    parser.add_argument("--dt", type=float, default=0.002)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--case-seconds", type=float, default=120)
    parser.add_argument("--out")
    args = parser.parse_args()
    if args.child:
        return child(args)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))  # (the finally clauses kill the busy processes)
    builds = [tuple(b.split("=", 1)) for b in args.builds.split(",")]
    cases = [(name, path, threads, False) for name, path in builds for threads in (1, os.cpu_count())]
    if args.passive:
        cases.append(("passive " + builds[0][0], builds[0][1], os.cpu_count(), True))
    rows = {}
    for r in range(args.rounds):
        for busy in (0, args.busy):
            for case in (cases if r % 2 == 0 else cases[::-1]):
                name, path, threads, passive = case
                if passive and busy == 0:
                    continue
                rows.setdefault((busy, name, threads), []).append(measure(args, os.path.abspath(path), threads,
                                                                          passive, busy))
                print(busy, name, threads, rows[(busy, name, threads)][-1], file=sys.stderr, flush=True)
    lines = ["| busy processes | build | threads | step, ms (median of the rounds' medians) | mean step, ms |"
             " against one thread of the same build |", "|---:|---|---:|---:|---:|---:|"]
    for (busy, name, threads), values in rows.items():
        median = statistics.median(v[0] for v in values)
        mean = statistics.median(v[1] for v in values)
        one = rows.get((busy, name.removeprefix("passive "), 1))
        ratios = [v[0] / o[0] for v, o in zip(values, one)] if one else []
        ratio = f"{statistics.median(ratios):.2f}×" if ratios else ""
        lines.append(f"| {busy} | {name} | {threads} | {median:.3f} | {mean:.3f} | {ratio} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        with open(args.out, "a") as f:
            f.write(text)


if __name__ == "__main__":
    main()
