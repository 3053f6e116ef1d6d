"""The table of tools/bench_ab.sh's runs: per scene and precision, NovaPhy's robot-steps/s over MuJoCo's
(BM_PairedStep's ratio) before and after, medians of the runs, and after over before.

    python3 tools/bench_ab_report.py OUT_DIR
"""

import glob
import json
import os
import re
import statistics
import sys

SCENES = {0: "chain15", 1: "quadruped, no floor", 2: "quadruped standing", 3: "humanoid.xml, no floor",
          4: "quadruped standing, pgs_tolerance 0"}


def main(folder):
    ratios = {}
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        side, scene, precision = re.match(r"(before|after)_s(\d)_p(\d)_", os.path.basename(path)).groups()
        with open(path) as f:
            for run in json.load(f)["benchmarks"]:
                ratios.setdefault((int(scene), int(precision)), {}).setdefault(side, []).append(run["ratio"])
    print("| scene | precision | NovaPhy / MuJoCo before (runs) | after (runs) | after / before |")
    print("|---|---|---|---|---|")
    for (scene, precision), sides in sorted(ratios.items()):
        before, after = sides.get("before", []), sides.get("after", [])
        if not before or not after:
            continue
        runs = lambda xs: ", ".join(f"{x:.2f}" for x in xs)
        b, a = statistics.median(before), statistics.median(after)
        print(f"| {SCENES[scene]} | {'float32' if precision else 'float64'} | {b:.2f} ({runs(before)}) | "
              f"{a:.2f} ({runs(after)}) | {a / b:.3f} |")


if __name__ == "__main__":
    main(sys.argv[1])
