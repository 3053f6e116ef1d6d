"""What the Go1 environment's twelve foot sensors (each foot's framepos, framelinvel and touch) cost a step: 1024
float32 Go1 worlds, collide + step five times in one novaphy.simulate call, with and without the sensors, in
alternating rounds in one process; medians over the rounds.
    build/venv/bin/python bench/sensor_cost.py [--worlds 1024] [--rounds 9] [--threads 0]"""
import argparse
import statistics
import time

import novaphy
import novaphy.envs


def simulator(worlds, sensors, threads):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(novaphy.envs.go1_scene())
    if sensors:
        novaphy.envs._with_foot_sensors(robot)
    builder = novaphy.ModelBuilder()
    builder.precision = novaphy.Precision.Float32
    builder.replicate(robot, worlds)
    model = builder.finalize()
    state, control = model.state(keyframe="home"), model.control(keyframe="home")
    pipeline = novaphy.CollisionPipeline(model, num_threads=threads)
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.num_threads = threads
    contacts = pipeline.contacts()
    return lambda: novaphy.simulate(pipeline, solver, state, control, contacts, 5, 0.004)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", type=int, default=1024)
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    runs = {sensors: simulator(args.worlds, sensors, args.threads) for sensors in (False, True)}
    for run in runs.values():
        for _ in range(10):
            run()
    times = {False: [], True: []}
    for _ in range(args.rounds):
        for sensors, run in runs.items():
            start = time.perf_counter()
            for _ in range(10):
                run()
            times[sensors].append((time.perf_counter() - start) / 10 * 1e3)
    without, with_ = statistics.median(times[False]), statistics.median(times[True])
    ratios = statistics.median(w / o for w, o in zip(times[True], times[False]))
    print(f"| {args.worlds} | {args.threads or 'default'} | {without:.2f} | {with_:.2f} | {ratios:.3f} |")


if __name__ == "__main__":
    main()
