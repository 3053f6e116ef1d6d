"""Wall time of each seed demo's run() (bindings/python/demos/multibody_demo) at its default step count,
the fastest of `repeats` runs, as JSON: one world on the Python API, the single-world end of the scale.

    PYTHONPATH=build/python OMP_NUM_THREADS=1 /usr/bin/python3 tools/time_demos.py [repeats]
"""

import importlib
import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bindings", "python", "demos", "multibody_demo"))

STEPS = {"demo_100_robots": 400, "demo_motor_arm": 600, "demo_newtons_cradle_pendulum": 2000, "demo_rope": 1200,
         "demo_seesaw": 360, "demo_wrecking_ball": 720}


def main(repeats):
    seconds = {}
    for name, steps in STEPS.items():
        demo = importlib.import_module(name)
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            demo.run(steps)
            times.append(time.perf_counter() - start)
        seconds[name] = min(times)
    print(json.dumps(seconds))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 9)
