"""Trains the Go1 joystick policy (novaphy.envs' NovaPhy/Go1Joystick-v0) with PPO in JAX on the CPU, and reports
what it reached: the learning curve (PNG), the tracking error at a commanded 0.5 m/s forward over `--eval-worlds`
worlds, and a GIF of the policy walking.

The optional training extra (JAX, optax) lives in its own virtual environment, build/venv-train (tools/setup_train.sh
makes it); nothing else needs it:
    bash tools/setup_train.sh
    PYTHONPATH=build/python build/venv-train/bin/python tools/train_go1.py --minutes 60 --out bench/results/train_go1
    PYTHONPATH=build/python build/venv-train/bin/python tools/train_go1.py --iterations 2 --worlds 64 --out /tmp/smoke

PPO (Schulman et al. 2017) with generalised advantage estimation, a Gaussian policy of learned log standard deviation,
observations normalised by running statistics, truncated episodes bootstrapped from their final observation;
the networks and their Adam steps in JAX (optax for Adam and clipping)."""
import argparse
import json
import math
import os
import time
from functools import partial

import numpy as np

import gymnasium
import jax
import jax.numpy as jnp
import optax

import novaphy
import novaphy.envs  # noqa: F401  (registers the environments)

HIDDEN_POLICY = (128, 128, 128)
HIDDEN_VALUE = (128, 128, 128)


def init_mlp(key, sizes):
    params = []
    for n_in, n_out in zip(sizes[:-1], sizes[1:]):
        key, sub = jax.random.split(key)
        params.append((jax.random.normal(sub, (n_in, n_out)) * math.sqrt(2.0 / n_in), jnp.zeros(n_out)))
    return params


def mlp(params, x):
    for w, b in params[:-1]:
        x = jax.nn.swish(x @ w + b)
    w, b = params[-1]
    return x @ w + b


def init_params(key, obs_size, action_size):
    k1, k2 = jax.random.split(key)
    policy = init_mlp(k1, (obs_size, *HIDDEN_POLICY, action_size))
    policy[-1] = (policy[-1][0] * 0.01, policy[-1][1])  # small first actions: the robot starts standing
    return {"policy": policy, "log_std": jnp.full(action_size, -1.0), "value": init_mlp(k2, (obs_size, *HIDDEN_VALUE, 1))}


def log_prob(mean, log_std, action):
    return jnp.sum(-0.5 * ((action - mean) / jnp.exp(log_std)) ** 2 - log_std - 0.5 * math.log(2 * math.pi), axis=-1)


@jax.jit
def act(params, obs, key):
    mean = mlp(params["policy"], obs)
    action = mean + jnp.exp(params["log_std"]) * jax.random.normal(key, mean.shape)
    return action, log_prob(mean, params["log_std"], action), mlp(params["value"], obs)[:, 0]


@jax.jit
def mean_action(params, obs):
    return mlp(params["policy"], obs)


@jax.jit
def value(params, obs):
    return mlp(params["value"], obs)[:, 0]


def loss_fn(params, batch, clip, value_coef, entropy_coef):
    mean = mlp(params["policy"], batch["obs"])
    new_log_prob = log_prob(mean, params["log_std"], batch["action"])
    ratio = jnp.exp(new_log_prob - batch["log_prob"])
    adv = (batch["adv"] - batch["adv"].mean()) / (batch["adv"].std() + 1e-8)
    policy_loss = -jnp.mean(jnp.minimum(ratio * adv, jnp.clip(ratio, 1 - clip, 1 + clip) * adv))
    value_loss = jnp.mean((mlp(params["value"], batch["obs"])[:, 0] - batch["ret"]) ** 2)
    entropy = jnp.sum(params["log_std"] + 0.5 * math.log(2 * math.pi * math.e))
    return policy_loss + value_coef * value_loss - entropy_coef * entropy, (policy_loss, value_loss)


@partial(jax.jit, static_argnames=("optimizer",))
def update(params, opt_state, batch, optimizer, clip=0.2, value_coef=0.5, entropy_coef=0.005):
    (loss, parts), grads = jax.value_and_grad(loss_fn, has_aux=True)(params, batch, clip, value_coef, entropy_coef)
    updates, opt_state = optimizer.update(grads, opt_state, params)
    return optax.apply_updates(params, updates), opt_state, loss, parts


class RunningNorm:
    """Observation statistics over everything seen (Welford's update over batches)."""

    def __init__(self, size):
        self.count, self.mean, self.var = 1e-4, np.zeros(size), np.ones(size)

    def update(self, x):
        n, mean, var = len(x), x.mean(axis=0), x.var(axis=0)
        delta, total = mean - self.mean, self.count + n
        self.mean = self.mean + delta * n / total
        self.var = (self.var * self.count + var * n + delta**2 * self.count * n / total) / total
        self.count = total

    def __call__(self, x):
        return np.clip((x - self.mean) / np.sqrt(self.var + 1e-8), -10, 10).astype(np.float32)


def evaluate(params, norm, worlds, seconds, command=(0.5, 0.0, 0.0), seed=1, frames=None):
    """The mean |forward velocity - command| over the worlds and the last half of `seconds` with the policy's mean
    action (no noise, no randomisation), and the share of worlds that did not fall; `frames` collects world 0's
    states for the GIF."""
    env = novaphy.envs.Go1Joystick(worlds, noise=False, randomize=False, command=command, episode_steps=10**9)
    obs, _ = env.reset(seed=seed)
    steps = int(seconds / novaphy.envs.CTRL_DT)
    errors, fell = [], np.zeros(worlds, bool)
    for k in range(steps):
        obs, _, terminated, _, _ = env.step(np.asarray(mean_action(params, norm(obs))))
        fell |= terminated
        if frames is not None and k % 2 == 0:
            frames.append(np.array(env.state.body_q))
        if k >= steps // 2:  # the observation's first entry: the trunk's forward velocity in its frame (no noise)
            errors.append(np.abs(obs[:, 0] - command[0]))
    return float(np.mean(errors)), float(1 - fell.mean()), env


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", type=int, default=1024)
    parser.add_argument("--horizon", type=int, default=24, help="control steps per world per iteration")
    parser.add_argument("--minutes", type=float, default=60.0, help="training wall time")
    parser.add_argument("--iterations", type=int, default=0, help="stop after this many iterations (0: by time)")
    parser.add_argument("--epochs", type=int, default=4)
    parser.add_argument("--minibatches", type=int, default=4)
    parser.add_argument("--lr", type=float, default=3e-4)
    parser.add_argument("--gamma", type=float, default=0.97)
    parser.add_argument("--lam", type=float, default=0.95)
    parser.add_argument("--eval-worlds", type=int, default=1000)
    parser.add_argument("--eval-seconds", type=float, default=6.0)
    parser.add_argument("--gif-seconds", type=float, default=4.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="bench/results/train_go1")
    parser.add_argument("--reward-scale", action="append", default=[], metavar="TERM=SCALE",
                        help="replace Playground's scale of a reward term (repeatable), e.g. feet_clearance=0")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    reward_scales = {}
    for given in args.reward_scale:
        term, _, scale = given.partition("=")
        reward_scales[term] = float(scale)

    env = gymnasium.make_vec("NovaPhy/Go1Joystick-v0", num_envs=args.worlds, vectorization_mode="vector_entry_point",
                             reward_scales=reward_scales)
    obs_size, action_size = env.single_observation_space.shape[0], env.single_action_space.shape[0]
    key = jax.random.PRNGKey(args.seed)
    key, sub = jax.random.split(key)
    params = init_params(sub, obs_size, action_size)
    optimizer = optax.chain(optax.clip_by_global_norm(1.0), optax.adam(args.lr))
    opt_state = optimizer.init(params)
    norm = RunningNorm(obs_size)

    raw, _ = env.reset(seed=args.seed)
    norm.update(raw)
    start, curve, iteration = time.time(), [], 0
    episode_reward, finished = np.zeros(args.worlds), []
    T, N = args.horizon, args.worlds
    while True:
        elapsed = time.time() - start
        if (args.iterations and iteration >= args.iterations) or (not args.iterations and elapsed > 60 * args.minutes):
            break
        rollout_start = time.time()
        buf = {k: [] for k in ("obs", "action", "log_prob", "value", "reward", "done")}
        env_reward = 0.0  # the environment's own rewards (the curve), without the bootstrapped values
        for _ in range(T):
            obs = norm(raw)
            key, sub = jax.random.split(key)
            action, lp, v = (np.asarray(x) for x in act(params, obs, sub))
            raw, reward, terminated, truncated, info = env.step(action)
            reward = reward.astype(np.float64)
            env_reward += float(reward.mean()) / T
            if truncated.any():  # bootstrap a cut episode from its last observation
                final = norm(np.asarray(info["final_obs"]))
                reward = reward + args.gamma * truncated * np.asarray(value(params, final))
            episode_reward += reward
            done = terminated | truncated
            finished.extend(episode_reward[done].tolist())
            episode_reward[done] = 0
            for name, x in (("obs", obs), ("action", action), ("log_prob", lp), ("value", v), ("reward", reward),
                            ("done", done)):
                buf[name].append(x)
            norm.update(raw)
        values = np.stack(buf["value"] + [np.asarray(value(params, norm(raw)))])
        rewards, dones = np.stack(buf["reward"]), np.stack(buf["done"]).astype(np.float64)
        adv, last = np.zeros((T, N)), np.zeros(N)
        for t in reversed(range(T)):
            delta = rewards[t] + args.gamma * values[t + 1] * (1 - dones[t]) - values[t]
            last = delta + args.gamma * args.lam * (1 - dones[t]) * last
            adv[t] = last
        batch = {
            "obs": np.concatenate(buf["obs"]),
            "action": np.concatenate(buf["action"]),
            "log_prob": np.concatenate(buf["log_prob"]),
            "adv": adv.reshape(-1).astype(np.float32),
            "ret": (adv + values[:-1]).reshape(-1).astype(np.float32),
        }
        update_start = time.time()
        size = T * N // args.minibatches
        rng = np.random.default_rng(iteration)
        for _ in range(args.epochs):
            order = rng.permutation(T * N)
            for m in range(args.minibatches):
                pick = order[m * size : (m + 1) * size]
                params, opt_state, loss, (pl, vl) = update(params, opt_state, {k: x[pick] for k, x in batch.items()},
                                                           optimizer)
        jax.block_until_ready(params)
        iteration += 1
        steps = iteration * T * N
        mean_reward = float(np.mean(finished[-200:])) if finished else float("nan")
        curve.append({"iteration": iteration, "env_steps": steps, "minutes": (time.time() - start) / 60,
                      "step_reward": env_reward, "episode_reward": mean_reward,
                      "value_loss": float(vl), "std": float(np.exp(params["log_std"]).mean()),
                      "rollout_s": update_start - rollout_start, "update_s": time.time() - update_start})
        if iteration % 10 == 0 or iteration == 1:
            c = curve[-1]
            print(f"it {iteration:5d}  {c['minutes']:6.1f} min  {steps / 1e6:7.2f} M steps  reward/step "
                  f"{c['step_reward']:.4f}  value loss {c['value_loss']:.4f}  std {c['std']:.3f}  rollout "
                  f"{c['rollout_s']:.2f} s  update {c['update_s']:.2f} s", flush=True)

    error, standing, eval_env = evaluate(params, norm, args.eval_worlds, args.eval_seconds)
    summary = {"iterations": iteration, "env_steps": iteration * T * N, "minutes": (time.time() - start) / 60,
               "forward_error_m_s": error, "standing_share": standing, "command_m_s": 0.5,
               "eval_worlds": args.eval_worlds, "worlds": N, "horizon": T, "reward_scales": reward_scales}
    print(json.dumps(summary), flush=True)
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump({"summary": summary, "curve": curve}, f, indent=1)
    plot(curve, os.path.join(args.out, "curve.png"))
    gif(params, norm, os.path.join(args.out, "walk.gif"), args.gif_seconds)


def plot(curve, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot([c["env_steps"] / 1e6 for c in curve], [c["step_reward"] for c in curve])
    ax.set_xlabel("env steps (millions)")
    ax.set_ylabel("mean reward per control step")
    ax.set_title("Go1 joystick, PPO on NovaPhy (2-core CPU)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def gif(params, norm, path, seconds):
    from novaphy import viewer

    frames = []
    _, _, env = evaluate(params, norm, 1, seconds, frames=frames)
    viewer.save_gif(env.model, frames, path, fps=25)


if __name__ == "__main__":
    main()
