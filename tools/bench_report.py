"""Turns the JSON of novaphy_bench_step and novaphy_bench_batch (Google Benchmark, --benchmark_format=json)
into the README's markdown tables and a throughput plot.

    /usr/bin/python3 tools/bench_report.py step.json batch.json [--out PREFIX]

Writes PREFIX.md and PREFIX.png (default bench/results/bench). Robot-steps per second are medians over
repetitions when the JSON has them; ratios set NovaPhy against MuJoCo measured in the same run.
"""

import argparse
import json
import os
import statistics
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the headless backend is chosen)

STEP_SCENES = ["chain15", "quadruped, no floor", "quadruped standing", "humanoid.xml",
               "quadruped standing, pgs_tolerance 0"]
# the MuJoCo run a scene is set against: the tolerance only changes NovaPhy's settings
MUJOCO_SCENE = {4: 2}
BATCH_SCENES = ["chain15", "quadruped", "humanoid.xml"]
PRECISION = ["float64", "float32"]
MASS_KERNELS = ["CRBA", "tiled product"]


def runs(path):
    """(name without repetition suffix, the benchmark's entries) of every iteration run in a JSON file."""
    with open(path) as f:
        data = json.load(f)
    grouped = defaultdict(list)
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        grouped[b["run_name"] if "run_name" in b else b["name"]].append(b)
    return grouped, data.get("context", {})


def median(entries, key):
    return statistics.median(float(e[key]) for e in entries)


def cell(entry, key):
    """A counter to two places, or a dash where the run predates it (BM_PairedStep's per-core counters)."""
    return f"{float(entry[key]):.2f}" if key in entry else "–"


def step_tables(path):
    grouped, context = runs(path)
    rate = {}  # (engine, scene, precision, worlds, threads) -> robot-steps/s
    mjdata = {}  # scene -> MuJoCo's mjData bytes per world
    memory = {}  # (scene, precision) -> (bytes per world at 4096 worlds, state + H + factor bytes)
    height = {}  # (engine, scene, precision, worlds, threads) -> the floor scenes' mean base height at the end
    paired = {}  # (scene, precision) -> BM_PairedStep's counters
    for name, entries in grouped.items():
        e = entries[0]
        if name.startswith("BM_PairedStep"):
            paired[(int(e["scene"]), int(e["precision"]))] = e
            continue
        engine = "novaphy" if name.startswith("BM_NovaPhyStep") else "mujoco"
        key = (engine, int(e["scene"]), int(e["precision"]), int(e["worlds"]), int(e["threads"]))
        rate[key] = median(entries, "items_per_second")
        if "base_height" in e:
            height[key] = median(entries, "base_height")
        if engine == "mujoco":
            mjdata[key[1]] = float(e["mjdata_bytes_per_world"])
        if engine == "novaphy" and int(e["worlds"]) == 4096 and int(e["threads"]) == 1:
            memory[(key[1], key[2])] = (float(e["solver_bytes_per_world"]), float(e["state_bytes_per_world"]),
                                        float(e["h_factor_bytes_per_world"]))
    all_threads = max(k[4] for k in rate)
    lines = [
        f"Whole steps, robot-steps/s (medians), {all_threads} threads unless noted; MuJoCo 2.2.2 steps the same",
        "MJCF with one mjData per world in the same OpenMP loop (to 4096 worlds: 16384 of its ~14 MB mjData",
        "do not fit in this machine's 24 GiB). Ratios are NovaPhy / MuJoCo.",
        "",
        "| scene | worlds | MuJoCo | NovaPhy float64 | ratio | NovaPhy float32 | ratio |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    worlds_list = sorted({k[3] for k in rate})
    for scene in sorted({k[1] for k in rate}):
        for worlds in worlds_list:
            mj = rate.get(("mujoco", MUJOCO_SCENE.get(scene, scene), 0, worlds, all_threads))
            cells = [STEP_SCENES[scene], f"{worlds}", f"{mj:,.0f}" if mj else "(not run)"]
            for precision in (0, 1):
                n = rate.get(("novaphy", scene, precision, worlds, all_threads))
                cells += [f"{n:,.0f}", f"{n / mj:.1f}x" if mj else ""] if n else ["", ""]
            lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Thread scaling at 4096 worlds (robot-steps/s, one thread and all):", ""]
    lines += ["| scene | engine | 1 thread | all threads | speed-up |", "|---|---|---:|---:|---:|"]
    for scene in sorted({k[1] for k in rate}):
        for engine, precision, label in (("mujoco", 0, "MuJoCo"), ("novaphy", 0, "NovaPhy float64"),
                                         ("novaphy", 1, "NovaPhy float32")):
            one = rate.get((engine, scene, precision, 4096, 1))
            many = rate.get((engine, scene, precision, 4096, all_threads))
            if one and many:
                lines.append(f"| {STEP_SCENES[scene]} | {label} | {one:,.0f} | {many:,.0f} | {many / one:.2f}x |")
    standing = []
    for scene in sorted({k[1] for k in height if k[0] == "novaphy"}):
        z = [height.get(k, 0) for k in (("mujoco", MUJOCO_SCENE.get(scene, scene), 0, 4096, all_threads),
                                        ("novaphy", scene, 0, 4096, all_threads),
                                        ("novaphy", scene, 1, 4096, all_threads))]
        standing.append(f"{STEP_SCENES[scene]}: MuJoCo {z[0]:.4f}, NovaPhy float64 {z[1]:.4f}, float32 {z[2]:.4f}")
    if standing:
        lines += ["", "The floor scenes' robots at the end of the 4096-world runs on all threads, mean base height "
                  "(m): " + "; ".join(standing)]
    if paired:
        rounds = int(next(iter(paired.values()))["iterations"])
        lines += ["", f"Side by side at 4096 worlds (BM_PairedStep): {rounds} rounds, each timing in turn NovaPhy on all "
                  "threads, NovaPhy on one thread pinned to each core, MuJoCo on all and MuJoCo on one pinned to each "
                  "core (the order rotating), each run after as many steps not timed as it times; medians over the "
                  "rounds of robot-steps/s and of each round's ratios. 1 → all: all threads over one thread on the "
                  "first core. Cores: the slowest core's one-thread rate over the fastest's (NovaPhy's; MuJoCo's), "
                  "two threads reach at most 1 + that times the fastest core's one thread; use: all threads over the one-thread rates on "
                  "the cores added (1: the threads lose nothing to each other). Steal: the share of the cores' time "
                  "the host gave to other guests meanwhile (Linux's steal time):", "",
                  "| scene | precision | NovaPhy | MuJoCo | ratio | NovaPhy 1 → all | MuJoCo 1 → all "
                  "| cores | NovaPhy use | MuJoCo use | steal |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for (scene, precision), e in sorted(paired.items()):
            lines.append(f"| {STEP_SCENES[scene]} | {PRECISION[precision]} | {float(e['novaphy_all']):,.0f} "
                         f"| {float(e['mujoco_all']):,.0f} | {float(e['ratio']):.1f}x "
                         f"| {float(e['novaphy_speedup']):.2f}x | {float(e['mujoco_speedup']):.2f}x "
                         f"| {cell(e, 'novaphy_core_spread')}; {cell(e, 'mujoco_core_spread')} "
                         f"| {cell(e, 'novaphy_core_use')} | {cell(e, 'mujoco_core_use')} "
                         f"| {100 * float(e['steal']):.0f} % |")
    lines += ["", "Memory per world at 4096 worlds, bytes: the solver's (batched blocks, scalar scratch, step vectors)",
              "plus the State's arrays, against the State's arrays plus H and its factor:", "",
              "| scene | precision | solver | state | solver + state | state + H + factor | ratio | MuJoCo mjData |",
              "|---|---|---:|---:|---:|---:|---:|---:|"]
    for (scene, precision), (solver, state, h) in sorted(memory.items()):
        lines.append(f"| {STEP_SCENES[scene]} | {PRECISION[precision]} | {solver:,.0f} | {state:,.0f} "
                     f"| {solver + state:,.0f} | {state + h:,.0f} | {(solver + state) / (state + h):.2f} "
                     f"| {mjdata.get(MUJOCO_SCENE.get(scene, scene), 0):,.0f} |")
    return lines, rate, all_threads, context


def batch_tables(path):
    grouped, _ = runs(path)
    peak = None
    rows = []
    for name, entries in grouped.items():
        if name.startswith("BM_FmaPeak"):
            peak = median(entries, "GFLOPs")
            continue
        e = entries[0]
        rows.append((int(e["scene"]), int(e["precision"]), int(e["worlds"]), int(e.get("kernel", 0)),
                     median(entries, "GFLOPs"), float(e["flops_per_world"]), median(entries, "items_per_second")))
    lines = [f"Batched mass matrix (CRBA, or use_tile_gemm's tiled product) + fused L^T L factor and solve on one",
             f"core (flop model in bench/batch_bench.cpp); measured FP32 FMA peak of the core: {peak:.1f} GFLOP/s.", "",
             "| scene | precision | worlds | mass matrix | flops/world | worlds/s | GFLOP/s | % of FP32 peak |",
             "|---|---|---:|---|---:|---:|---:|---:|"]
    for scene, precision, worlds, kernel, gflops, flops, items in sorted(rows):
        lines.append(f"| {BATCH_SCENES[scene]} | {PRECISION[precision]} | {worlds} | {MASS_KERNELS[kernel]} "
                     f"| {flops:,.0f} | {items:,.0f} | {gflops:.1f} | {100 * gflops / peak:.0f} % |")
    return lines


def plot(rate, all_threads, path):
    scenes = sorted({k[1] for k in rate})
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.2 * len(scenes), 3.6), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        for engine, precision, label, style in (("mujoco", 0, "MuJoCo 2.2.2", "k-o"),
                                                ("novaphy", 0, "NovaPhy float64", "b-s"),
                                                ("novaphy", 1, "NovaPhy float32", "r-^")):
            shown = MUJOCO_SCENE.get(scene, scene) if engine == "mujoco" else scene
            points = sorted((k[3], v) for k, v in rate.items()
                            if k[0] == engine and k[1] == shown and k[2] == precision and k[4] == all_threads)
            if points:
                ax.loglog([p[0] for p in points], [p[1] for p in points], style, label=label, ms=4)
        ax.set_title(STEP_SCENES[scene], fontsize=9)
        ax.set_xlabel("worlds")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel(f"robot-steps/s ({all_threads} threads)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("step_json")
    parser.add_argument("batch_json")
    parser.add_argument("--out", default="bench/results/bench")
    args = parser.parse_args()
    step_lines, rate, all_threads, context = step_tables(args.step_json)
    lines = [f"<!-- {os.path.basename(args.step_json)}: {context.get('num_cpus', '?')} CPUs at "
             f"{context.get('mhz_per_cpu', '?')} MHz, {context.get('date', '')} -->", ""]
    lines += step_lines + [""] + batch_tables(args.batch_json)
    with open(args.out + ".md", "w") as f:
        f.write("\n".join(lines) + "\n")
    plot(rate, all_threads, args.out + ".png")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
