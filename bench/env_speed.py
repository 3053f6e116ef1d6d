"""The Go1 vector environment's env-steps/s (NovaPhy/Go1Joystick-v0: a control step of five 0.004 s steps,
observations, rewards and resets in the loop) beside raw collide + step of the same worlds (five steps per env-step),
and beside the same task on today's MuJoCo (mujoco.rollout of the worlds on a pool of threads, five steps a call,
the observation and the reward's tracking terms made with numpy from its qpos and qvel), 1024 and 4096 worlds, one
thread (pinned to CPU 0) and two; each case in a process of its own, medians of `reps` timings of `steps` env-steps.
    build/venv/bin/python bench/env_speed.py [--worlds 1024,4096] [--reps 5] [--steps 20] > bench/results/env_speed.md"""
import argparse
import os
import subprocess
import sys

RUN = r"""
import statistics, sys, time
import numpy as np
import gymnasium
import novaphy.envs
kind, worlds, threads, reps, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
rng = np.random.default_rng(0)
actions = rng.uniform(-0.3, 0.3, (steps, worlds, 12))
times = []
if kind in ("env", "raw"):
    env = gymnasium.make_vec("NovaPhy/Go1Joystick-v0", num_envs=worlds, vectorization_mode="vector_entry_point",
                             threads=threads)
    env.reset(seed=0)
    for k in range(5):
        env.step(actions[k])
    for _ in range(reps):
        start = time.perf_counter()
        if kind == "env":
            for k in range(steps):
                env.step(actions[k])
        else:
            for k in range(5 * steps):
                env.pipeline.collide(env.state, env.contacts)
                env.solver.step(env.state, env.state, env.control, env.contacts, 0.004)
        times.append((time.perf_counter() - start) / steps)
else:
    import mujoco
    from mujoco import rollout
    m = mujoco.MjModel.from_xml_path(novaphy.envs.go1_scene())
    m.opt.timestep = 0.004
    m.actuator_gainprm[:, 0] = 35.0
    m.actuator_biasprm[:, 1] = -35.0
    m.actuator_biasprm[:, 2] = -0.5
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, state0, spec)
    state = np.tile(state0, (worlds, 1))
    datas = [mujoco.MjData(m) for _ in range(threads)]
    home = m.key_qpos[0, 7:]
    command = np.tile([0.5, 0.0, 0.0], (worlds, 1))
    def rotate_into(q, v):  # q [w, x, y, z]
        u, w = -q[:, 1:4], q[:, 0:1]
        t = 2.0 * np.cross(u, v)
        return v + w * t + np.cross(u, t)
    def env_step(state, action):
        control = np.repeat((home + 0.5 * action)[:, None, :], 5, axis=1)
        states, _ = rollout.rollout(m, datas, state, control, nstep=5, persistent_pool=True)
        state = states[:, -1]
        qpos, qvel = state[:, 1:1 + m.nq], state[:, 1 + m.nq:1 + m.nq + m.nv]
        quat = qpos[:, 3:7]
        linvel = rotate_into(quat, qvel[:, 0:3])
        gravity = rotate_into(quat, np.tile([0.0, 0.0, -1.0], (worlds, 1)))
        obs = np.concatenate([linvel, qvel[:, 3:6], gravity, qpos[:, 7:] - home, qvel[:, 6:], action, command], 1)
        reward = np.exp(-np.sum((command[:, :2] - linvel[:, :2]) ** 2, 1) / 0.25) + np.exp(-qvel[:, 5] ** 2 / 0.25)
        return state, obs.astype(np.float32), reward
    for k in range(5):
        state, _, _ = env_step(state, actions[k])
    for _ in range(reps):
        start = time.perf_counter()
        for k in range(steps):
            state, obs, reward = env_step(state, actions[k])
        times.append((time.perf_counter() - start) / steps)
    rollout.shutdown_persistent_pool()
print(worlds / statistics.median(times))
"""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--worlds", default="1024,4096")
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    env = dict(os.environ, PYTHONPATH=os.path.join(here, "..", "build", "python"), OMP_WAIT_POLICY="passive")
    print(f"env-steps/s (a control step of 0.02 s = five 0.004 s steps), medians of {args.reps} timings of "
          f"{args.steps} env-steps\n")
    print("| worlds | threads | raw collide + step | NovaPhy env | env / raw | MuJoCo 4.0 rollout env | "
          "NovaPhy env / MuJoCo env |")
    print("|---|---|---|---|---|---|---|")
    for worlds in map(int, args.worlds.split(",")):
        for threads in (1, 2):
            rates = {}
            for kind in ("raw", "env", "mujoco"):
                pin = ["taskset", "-c", "0"] if threads == 1 else []
                done = subprocess.run(pin + [sys.executable, "-c", RUN, kind, str(worlds), str(threads),
                                             str(args.reps), str(args.steps)], env=env, capture_output=True, text=True)
                if done.returncode != 0:
                    sys.exit(done.stderr)
                rates[kind] = float(done.stdout)
            print(f"| {worlds} | {threads} | {rates['raw']:.0f} | {rates['env']:.0f} | "
                  f"{rates['env'] / rates['raw']:.2f} | {rates['mujoco']:.0f} | {rates['env'] / rates['mujoco']:.1f} |",
                  flush=True)


if __name__ == "__main__":
    main()
