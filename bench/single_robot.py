"""One robot's forward dynamics: NovaPhy (ForwardDynamics, both precisions), MuJoCo 2.2.2's mj_forward (both from
novaphy_bench_dynamics) and Pinocchio's ABA, RNEA and CRBA (bench/pinocchio_dynamics.py, `pin` from PyPI in
build/venv-pin, made here on first use), alternating rounds in one run; writes a markdown table of medians.

    python3 bench/single_robot.py [--rounds 3] [--out bench/results/single_robot_pinocchio.md]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SCENES = [
    os.path.join(ROOT, "bench", "scenes", "chain15.xml"),
    os.path.join(ROOT, "bench", "scenes", "quadruped.xml"),
    "/usr/share/mujoco/model/humanoid/humanoid.xml",
]
NAMES = ["chain15", "quadruped", "humanoid"]


def pinocchio_python():
    venv = os.path.join(ROOT, "build", "venv-pin")
    python = os.path.join(venv, "bin", "python")
    if not os.path.exists(python):
        subprocess.run(["/usr/bin/python3", "-m", "venv", venv], check=True)
        subprocess.run([python, "-m", "pip", "install", "-q", "--disable-pip-version-check", "pin==4.1.0"], check=True)
    return python


def novaphy_and_mujoco(bench):
    out = subprocess.run(
        [bench, "--benchmark_filter=BM_MujocoForward|BM_NovaPhyForwardDynamics", "--benchmark_min_time=0.3",
         "--benchmark_repetitions=3", "--benchmark_report_aggregates_only=true", "--benchmark_format=json"],
        capture_output=True, text=True, check=True).stdout
    times = {}
    for b in json.loads(out)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            times[b["run_name"]] = b["real_time"] / 1000  # ns -> us
    return times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--bench", default=os.path.join(ROOT, "build", "bench", "novaphy_bench_dynamics"))
    parser.add_argument("--out")
    args = parser.parse_args()
    python = pinocchio_python()
    runs, pins = [], []
    for _ in range(args.rounds):
        runs.append(novaphy_and_mujoco(args.bench))
        pins.append(json.loads(subprocess.run([python, os.path.join(ROOT, "bench", "pinocchio_dynamics.py"), *SCENES],
                                              capture_output=True, text=True, check=True).stdout))
    med = lambda values: statistics.median(values)  # noqa: E731
    lines = ["| scene | NovaPhy ForwardDynamics float64 | float32 | MuJoCo 2.2.2 `mj_forward` | Pinocchio ABA | "
             "Pinocchio RNEA | Pinocchio CRBA | NovaPhy / mj_forward | NovaPhy / Pinocchio ABA |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for i, (scene, name) in enumerate(zip(SCENES, NAMES)):
        f64 = med([r[f"BM_NovaPhyForwardDynamics/{i}/0"] for r in runs])
        f32 = med([r[f"BM_NovaPhyForwardDynamics/{i}/1"] for r in runs])
        mj = med([r[f"BM_MujocoForward/{i}"] for r in runs])
        aba, rnea, crba = (med([p[scene][k] for p in pins]) for k in ("aba", "rnea", "crba"))
        lines.append(f"| {name} (nv {pins[0][scene]['nv']}) | {f64:.2f} µs | {f32:.2f} µs | {mj:.2f} µs | {aba:.2f} µs | "
                     f"{rnea:.2f} µs | {crba:.2f} µs | {f64 / mj:.2f}× | {f64 / aba:.2f}× |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write("# One robot: NovaPhy beside MuJoCo 2.2.2 and Pinocchio\n\n"
                    f"Medians of {args.rounds} alternating rounds (each of NovaPhy and MuJoCo itself a median of 3) "
                    f"from `python3 bench/single_robot.py --rounds {args.rounds} --out {args.out}`; Pinocchio "
                    f"{pins[0]['pinocchio']} from PyPI, timed from Python with its binding's cost "
                    f"({med([p['overhead'] for p in pins]):.2f} µs a call, the same call on a model without joints) "
                    "taken off. NovaPhy's figure is a whole forward dynamics (input checks, control forces, FK, bias, "
                    "mass matrix, factor, solve), as is mj_forward's (constraints off); Pinocchio's ABA is the "
                    "accelerations from given joint forces, its RNEA the inverse dynamics, its CRBA the mass matrix "
                    "alone. Pinocchio reads the same MJCF with its own parser (its neutral configuration; the same "
                    "velocities and forces).\n\n" + text + "\n")


if __name__ == "__main__":
    main()
