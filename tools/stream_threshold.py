"""Where streaming the bodies' output pays on this machine: `stream_body_output_above` measured.

For each world count, two solvers of the same replicated MJCF step in alternating runs, one writing
body_q/body_qd with non-temporal stores always (stream_body_output_above = 0) and one never; each run
is timed after as many untimed steps as it times, the order flips from round to round, and the line
prints the median of the rounds' speed ratios (streamed / stored; above 1 streaming pays) with its
quartiles and the step's data in MB (the state's arrays and the solver's, what the setting compares).
The robots fall freely (no contacts are collided): the setting concerns the output, not the contacts.

  PYTHONPATH=build/python OMP_PROC_BIND=close OMP_PLACES=cores /usr/bin/python3 tools/stream_threshold.py \\
      --worlds 512,4096,16384 --precision Float32
"""
import argparse
import os
import statistics
import time

import novaphy


def world_counts(text):
    return [int(w) for w in text.split(",")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    scenes = os.path.join(os.path.dirname(__file__), "..", "bench", "scenes")
    parser.add_argument("--mjcf", default=os.path.join(scenes, "quadruped.xml"))
    parser.add_argument("--worlds", type=world_counts, default="512,4096,16384", help="comma-separated world counts")
    parser.add_argument("--precision", default="Float32", choices=["Float32", "Float64"])
    parser.add_argument("--rounds", type=int, default=30)
    args = parser.parse_args()
    if args.rounds < 2:
        parser.error(f"--rounds {args.rounds}: quartiles need at least 2")

    robot = novaphy.ModelBuilder()
    robot.add_mjcf(args.mjcf)
    for worlds in args.worlds:
        batch = novaphy.ModelBuilder()
        batch.precision = getattr(novaphy.Precision, args.precision)
        batch.replicate(robot, worlds)
        model = batch.finalize()
        arms = []
        for above in (0, 1 << 62):  # always, never
            solver = novaphy.solvers.SolverFeatherstone(model)
            solver.settings.stream_body_output_above = above
            arms.append((solver, model.state(), model.control(), novaphy.CollisionPipeline(model).contacts()))
        steps = max(5, 200000 // worlds)

        def seconds(arm):
            solver, state, control, contacts = arm
            for _ in range(steps):
                solver.step(state, state, control, contacts, 0.005)
            start = time.perf_counter()
            for _ in range(steps):
                solver.step(state, state, control, contacts, 0.005)
            return time.perf_counter() - start

        ratios = []
        for r in range(args.rounds):
            t = [0.0, 0.0]
            for arm in (0, 1) if r % 2 == 0 else (1, 0):
                t[arm] = seconds(arms[arm])
            ratios.append(t[1] / t[0])
        low, _, high = statistics.quantiles(ratios, n=4)
        solver, state = arms[0][0], arms[0][1]
        arrays = (state.joint_q, state.joint_qd, state.body_q, state.body_qd, state.body_f)
        megabytes = (solver.memory_bytes + sum(a.nbytes for a in arrays)) / 1e6
        print(f"{worlds:6d} worlds {args.precision}, {megabytes:.1f} MB: streamed/stored "
              f"{statistics.median(ratios):.3f} (quartiles {low:.3f}-{high:.3f}), {steps} steps a run")


if __name__ == "__main__":
    main()
