"""Two builds' SolverFeatherstone.step side by side: Go1 (../shared/robots), the quadruped and humanoid.xml, float32
and float64, on one thread (pinned to CPU 0) and two, a build's run and the other's alternating before, after,
after, before in each round so that a slow spell of the machine lands on both, every case in each round. Each run
is a fresh process that replicates the robot, settles it 50 steps and times `steps` steps `reps` times (its
median); a round's ratio is the before build's time over the after build's (above 1: after is faster), the table
their median over the rounds. --before-settings NAME=VALUE,... sets the before side's solver settings: one build
given twice measures a setting's cost (soft_constraints=False: hard rows against MuJoCo's soft ones).
    build/venv/bin/python bench/ab_builds.py BEFORE/build/python AFTER/build/python [--rounds 5] > table.md"""
import argparse
import json
import os
import statistics
import subprocess
import sys

SCENES = {
    "go1": "../shared/robots/unitree_go1/scene.xml",
    "quadruped": "bench/scenes/quadruped.xml",
    "humanoid": "/usr/share/mujoco/model/humanoid/humanoid.xml",
}

RUN = r"""
import ast, json, statistics, sys, time
from replicated import replicated
scene, precision, threads, worlds, steps, reps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6])
model, state, control, solver, pipeline, contacts = replicated(scene, precision, threads, worlds)
for setting in filter(None, sys.argv[7].split(",")):
    name, value = setting.split("=")
    setattr(solver.settings, name, type(getattr(solver.settings, name))(ast.literal_eval(value)))
dt = 0.002
for _ in range(50):
    pipeline.collide(state, contacts)
    solver.step(state, state, control, contacts, dt)
times = []
for _ in range(reps):
    total = 0.0
    for _ in range(steps):
        pipeline.collide(state, contacts)
        start = time.perf_counter()
        solver.step(state, state, control, contacts, dt)
        total += time.perf_counter() - start
    times.append(total / steps)
print(json.dumps(statistics.median(times)))
"""


def run(build, scene, precision, threads, args, settings=""):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([build, os.path.dirname(os.path.abspath(__file__))]),
               OMP_WAIT_POLICY="passive")
    pin = ["taskset", "-c", "0"] if threads == 1 else []
    command = pin + [sys.executable, "-c", RUN, SCENES[scene], precision, str(threads), str(args.worlds),
                     str(args.steps), str(args.reps), settings]
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{build} {scene} {precision} {threads} threads failed:\n{done.stderr}")
    return json.loads(done.stdout)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--worlds", type=int, default=256)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--reps", type=int, default=9)
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated: go1, quadruped, humanoid")
    parser.add_argument("--precisions", default="Float32,Float64")
    parser.add_argument("--threads", default="1,2")
    parser.add_argument("--before-settings", default="", help="NAME=VALUE,... for the before side's solver")
    args = parser.parse_args()
    cases = [(scene, precision, threads) for scene in args.scenes.split(",")
             for precision in args.precisions.split(",") for threads in map(int, args.threads.split(","))]
    # the rounds outermost, every case in each, so that a slow spell of the machine lands on many cases' rounds
    # rather than on all of one case's
    ratios = {case: [] for case in cases}
    before = {case: [] for case in cases}
    after = {case: [] for case in cases}
    for r in range(args.rounds):
        for case in cases:
            b1 = run(args.before, *case, args, args.before_settings)
            a1 = run(args.after, *case, args)
            a2 = run(args.after, *case, args)
            b2 = run(args.before, *case, args, args.before_settings)
            before[case] += [b1, b2]
            after[case] += [a1, a2]
            ratios[case].append((b1 + b2) / (a1 + a2))
            print(f"round {r + 1} {' '.join(map(str, case))}: {ratios[case][-1]:.3f}", file=sys.stderr, flush=True)
    print(f"| scene | precision | threads | before ms | after ms | before / after (median of {args.rounds} rounds) |")
    print("|---|---|---|---|---|---|")
    for case in cases:
        scene, precision, threads = case
        print(f"| {scene} | {precision} | {threads} | {1e3 * statistics.median(before[case]):.3f} | "
              f"{1e3 * statistics.median(after[case]):.3f} | {statistics.median(ratios[case]):.3f} |")
    everything = [x for case in cases for x in ratios[case]]
    print(f"\nall {len(everything)} rounds of every case: median {statistics.median(everything):.3f}")


if __name__ == "__main__":
    main()
