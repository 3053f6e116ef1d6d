"""What a float32 model's float32 State and Control arrays cost from Python: the wall time of solver.step (one step)
and of novaphy.simulate (5 substeps, the Go1 env's decimation) called from Python, beside the solver's own time
inside them (serial_seconds, count_serial_time on); the rest is the call: for a float32 model the state and control
widened into the engine's double fields and the state rounded back, for a float64 model (the control) the call
alone. Go1 worlds at dt 0.002, one thread (pinned to CPU 0) and two; medians of `reps`.
    build/venv/bin/python bench/float32_arrays.py [--reps 15] > bench/results/float32_arrays.md"""
import argparse
import os
import subprocess
import sys

ROBOT = "../shared/robots/unitree_go1/scene.xml"

RUN = r"""
import statistics, sys, time
import novaphy
from replicated import replicated
robot_file, precision, threads, worlds, reps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
model, state, control, solver, pipeline, contacts = replicated(robot_file, precision, threads, worlds)
solver.settings.count_serial_time = True

def timed(call, steps):
    solver.reset_serial_seconds()
    start = time.perf_counter()
    call()
    wall = time.perf_counter() - start
    return wall, solver.serial_seconds["step"] / steps

def one_step():
    solver.step(state, state, control, contacts, 0.002)

def five_substeps():
    novaphy.simulate(pipeline, solver, state, control, contacts, 5, 0.002)

for _ in range(10):
    pipeline.collide(state, contacts)
    one_step()
step_rows, simulate_rows = [], []
for _ in range(reps):
    pipeline.collide(state, contacts)
    step_rows.append(timed(one_step, 1))
    simulate_rows.append(timed(five_substeps, 5))
def medians(rows):
    return statistics.median(w for w, _ in rows), statistics.median(s for _, s in rows)
print(*medians(step_rows), *medians(simulate_rows))
"""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--reps", type=int, default=15)
    args = parser.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([os.path.join(here, "..", "build", "python"), here]),
               OMP_WAIT_POLICY="passive")
    print(f"Worlds of {ROBOT} at dt 0.002; medians of {args.reps}. `python bench/float32_arrays.py "
          f"--reps {args.reps}`\n")
    print("| worlds | precision | threads | solver.step wall ms | its solver step ms | call's share | "
          "simulate(5) wall ms | its 5 steps ms | call's share |")
    print("|---|---|---|---|---|---|---|---|---|")
    for worlds in (1024, 4096):
        for precision in ("Float32", "Float64"):
            for threads in (1, 2):
                pin = ["taskset", "-c", "0"] if threads == 1 else []
                done = subprocess.run(pin + [sys.executable, "-c", RUN, ROBOT, precision, str(threads), str(worlds),
                                             str(args.reps)], env=env, capture_output=True, text=True)
                if done.returncode != 0:
                    sys.exit(done.stderr)
                wall, inner, sim_wall, sim_inner = map(float, done.stdout.split())
                print(f"| {worlds} | {precision} | {threads} | {1e3 * wall:.2f} | {1e3 * inner:.2f} | "
                      f"{(wall - inner) / wall:.3f} | {1e3 * sim_wall:.2f} | {5e3 * sim_inner:.2f} | "
                      f"{(sim_wall - 5 * sim_inner) / sim_wall:.3f} |", flush=True)


if __name__ == "__main__":
    main()
