"""Pinocchio's RNEA, CRBA and ABA on the MJCF scenes of novaphy_bench_dynamics, timed from Python with the
binding's own cost measured and taken off (the same call on a model without joints). Prints one JSON object:
{scene: {"nv": n, "rnea": us, "crba": us, "aba": us}, "overhead": us}. Run by bench/single_robot.py with the
interpreter that has `pin` (PyPI; its numpy 2 is not Debian's, so it lives in its own environment)."""

import json
import statistics
import sys
import time

import numpy as np
import pinocchio as pin


def per_call(fn, calls=20000, repeats=5):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        times.append((time.perf_counter() - start) / calls * 1e6)
    return statistics.median(times)


def main():
    empty = pin.Model()
    empty_data = empty.createData()
    none = np.zeros(0)
    overhead = per_call(lambda: pin.aba(empty, empty_data, none, none, none))
    out = {"overhead": overhead, "pinocchio": pin.__version__}
    for path in sys.argv[1:]:
        model = pin.buildModelFromMJCF(path)
        data = model.createData()
        q = pin.neutral(model)
        v = np.array([0.1 * (k % 5) - 0.2 for k in range(model.nv)])  # novaphy_bench_dynamics's qvel
        tau = np.full(model.nv, 0.3)
        out[path] = {
            "nv": model.nv,
            "rnea": per_call(lambda: pin.rnea(model, data, q, v, tau)) - overhead,
            "crba": per_call(lambda: pin.crba(model, data, q)) - overhead,
            "aba": per_call(lambda: pin.aba(model, data, q, v, tau)) - overhead,
        }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
