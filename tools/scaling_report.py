"""Turns the JSON of novaphy_bench_step's BM_ThreadSweep (tools/scaling.sh) into a markdown table: per scene,
precision and worlds, each thread count's robot-steps/s, speed-up over one thread and parallel efficiency for
NovaPhy and MuJoCo 2.2.2, NovaPhy's serial share of a step, and the ratio NovaPhy / MuJoCo.

    /usr/bin/python3 tools/scaling_report.py scaling.json [--out scaling.md]
"""

import argparse
import json
import os
import re

SCENES = {1: "quadruped, no floor", 2: "quadruped standing", 3: "humanoid.xml"}
PRECISION = ["float64", "float32"]


def rate(x):
    return f"{x / 1e6:.2f}M" if x >= 1e6 else f"{x / 1e3:.1f}k"


def table(data):
    lines = [
        "| scene | precision | worlds | threads | NovaPhy robot-steps/s | speed-up | efficiency | serial share "
        "| MuJoCo robot-steps/s | speed-up | efficiency | NovaPhy / MuJoCo |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for b in data["benchmarks"]:
        if not b["name"].startswith("BM_ThreadSweep"):
            continue
        threads = sorted(int(m.group(1)) for k in b if (m := re.fullmatch(r"novaphy_t(\d+)", k)))
        for t in threads:
            row = [SCENES[int(b["scene"])], PRECISION[int(b["precision"])], str(int(b["worlds"])), str(t),
                   rate(b[f"novaphy_t{t}"]), f"{b[f'novaphy_speedup_t{t}']:.2f}×",
                   f"{b[f'novaphy_efficiency_t{t}']:.2f}", f"{100 * b[f'serial_share_t{t}']:.1f} %"]
            if f"mujoco_t{t}" in b:
                row += [rate(b[f"mujoco_t{t}"]), f"{b[f'mujoco_speedup_t{t}']:.2f}×",
                        f"{b[f'mujoco_efficiency_t{t}']:.2f}", f"{b[f'ratio_t{t}']:.1f}×"]
            else:
                row += ["—", "—", "—", "—"]
            lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("json")
    parser.add_argument("--out", default="bench/results/scaling.md")
    args = parser.parse_args()
    with open(args.json) as f:
        data = json.load(f)
    context = data.get("context", {})
    head = (f"# Thread sweep\n\nMachine: {context.get('host_name', '?')}, {context.get('num_cpus', '?')} CPUs; "
            f"{os.path.basename(args.json)} from `bash tools/scaling.sh`. Medians over the rounds of one run; the "
            "serial share is the step's wall time outside its parallel work over the whole (the floor scene's collide "
            "with the solver's step: their serial_seconds)."
            "\n\n")
    with open(args.out, "w") as f:
        f.write(head + table(data))


if __name__ == "__main__":
    main()
