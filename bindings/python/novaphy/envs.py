"""Gymnasium vector environments on NovaPhy: `import novaphy.envs` registers

- ``NovaPhy/Go1Joystick-v0``: the Unitree Go1 tracks a velocity command (forward, sideways, turning) as MuJoCo
  Playground's Go1 joystick task defines it: its observation (local linear velocity, gyro, projected gravity, joint
  angles from the home pose, joint velocities, last action, command: 48 numbers), its action (12 joint targets about
  the home pose, scaled by 0.5), its control (Kp 35, Kd 0.5, 0.02 s control steps of five 0.004 s steps), its
  reward terms and scales (the feet terms from sensors the environment adds to each foot: its position, velocity
  and touch), its commands (new ones at random times within an episode) and its termination (the trunk upside
  down);
- ``NovaPhy/Go1Stand-v0``: the same robot and observation with a zero command, rewarded for standing in its home
  pose.

Both are vector environments only: ``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``.
Each of the N worlds is a Go1 in one NovaPhy model; a step sets the actuators' targets of every world, runs the
substeps in one call without the GIL (``novaphy.simulate``), and computes observations and rewards with numpy over
``world_view`` arrays. Worlds that end reset in the same step (``autoreset_mode`` SAME_STEP: the returned observation
is the new episode's first, ``info["final_obs"]`` the ended one's), each to the home keyframe with a new command and,
as Playground's, a random start (position within 0.5 m, any heading, the trunk moving at up to 0.5 m/s and rad/s
about each axis) and new per-world parameters (foot friction, link masses, trunk centre of mass, armature, friction
loss; see ``randomize_worlds``). The robot is ../shared/robots/unitree_go1 or the installed Menagerie's
(``robot=`` or NOVAPHY_GO1_SCENE give another scene file)."""
import os
from pathlib import Path

import numpy as np
import gymnasium
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

import novaphy
from .worlds import world_view

__all__ = ["Go1Joystick", "Go1Stand", "go1_scene"]

# MuJoCo Playground's Go1 joystick task (reward weights, command ranges, noise scales)
REWARD_SCALES = {
    "tracking_lin_vel": 1.0,
    "tracking_ang_vel": 0.5,
    "lin_vel_z": -0.5,
    "ang_vel_xy": -0.05,
    "orientation": -5.0,
    "dof_pos_limits": -1.0,
    "pose": 0.5,
    "termination": -1.0,
    "stand_still": -1.0,
    "torques": -0.0002,
    "action_rate": -0.01,
    "energy": -0.001,
    "feet_clearance": -2.0,
    "feet_height": -0.2,
    "feet_slip": -0.1,
    "feet_air_time": 0.1,
}
TRACKING_SIGMA = 0.25
MAX_FOOT_HEIGHT = 0.1
COMMAND_PERIOD = 5.0  # s: the mean time between new commands (exponentially distributed)
COMMAND_AMPLITUDE = np.array([1.5, 0.8, 1.2])  # forward, sideways (m/s), turning (rad/s)
COMMAND_KEPT = np.array([0.9, 0.25, 0.5])  # the chance a new command's entry is not zeroed
NOISE = {"joint_pos": 0.03, "joint_vel": 1.5, "gyro": 0.2, "gravity": 0.05, "linvel": 0.1}
KP, KD = 35.0, 0.5
ACTION_SCALE = 0.5
CTRL_DT, SIM_DT = 0.02, 0.004
EPISODE_STEPS = 1000
SOFT_LIMIT = 0.95
POSE_WEIGHTS = np.tile([1.0, 1.0, 0.1], 4)
FEET = ("FR", "FL", "RR", "RL")


def go1_scene():
    """The Go1 scene file: NOVAPHY_GO1_SCENE, else ../shared/robots/unitree_go1 beside this checkout, else the
    mujoco_menagerie package's copy where it is on disk (nothing is downloaded)."""
    given = os.environ.get("NOVAPHY_GO1_SCENE")
    if given:
        return given
    for parent in Path(__file__).resolve().parents:
        candidate = parent / "shared" / "robots" / "unitree_go1" / "scene.xml"
        if candidate.is_file():
            return str(candidate)
    try:
        import mujoco_menagerie

        cache = mujoco_menagerie.Cache()
        root = cache.root / "unitree_go1" if cache.root is not None else None
        if root is not None and (root / "scene.xml").is_file():
            return str(root / "scene.xml")
    except Exception:  # (no menagerie package, or none on disk)
        pass
    raise FileNotFoundError("NovaPhy's Go1 environments need the Menagerie Go1: pass robot='.../unitree_go1/scene.xml' "
                            "or set NOVAPHY_GO1_SCENE")


def _with_foot_sensors(robot_builder):
    """Each foot's position and velocity in the world (at the foot geom's centre, as Playground's foot sites) and
    its touch, as sensors of the robot: FR_pos, FR_linvel, FR_touch, ..."""
    robot = robot_builder.finalize()
    names = list(robot.shape_name)
    for foot in FEET:
        shape = names.index(foot)
        body = int(robot.shape_body[shape])
        frame = novaphy.Transform(robot.shape_transform[shape][:3])
        robot_builder.add_sensor("framepos", body, xform=frame, name=f"{foot}_pos")
        robot_builder.add_sensor("framelinvel", body, xform=frame, name=f"{foot}_linvel")
        robot_builder.add_sensor("touch", body, shape=shape, name=f"{foot}_touch")


def _quat_multiply(a, b):
    """a b of quaternions (n, 4) [x, y, z, w]."""
    av, aw, bv, bw = a[:, :3], a[:, 3:], b[:, :3], b[:, 3:]
    return np.concatenate([aw * bv + bw * av + np.cross(av, bv), aw * bw - np.sum(av * bv, axis=1, keepdims=True)],
                          axis=1)


def _rotate_into(q, v):
    """v (n, 3) in the frames of unit quaternions q (n, 4) [x, y, z, w]: R^T v."""
    u, w = -q[:, :3], q[:, 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


class Go1Joystick(VectorEnv):
    """num_envs Go1 worlds tracking velocity commands (module doc). precision: "Float32" (default) or "Float64";
    threads: the solver's and pipeline's (0: OpenMP's default); noise: Playground's observation noise;
    randomize: Playground's random start and new per-world parameters at each reset; command: a fixed (forward,
    sideways, turning) command for every world instead of random ones; reward_scales: {term: scale} replacing
    Playground's scales (REWARD_SCALES) of those terms."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}
    stand = False

    def __init__(self, num_envs=1, *, precision="Float32", threads=0, noise=True, randomize=True, command=None,
                 robot=None, episode_steps=EPISODE_STEPS, reward_scales=None):
        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"{type(self).__name__}: num_envs must be a positive integer, got {num_envs!r}")
        unknown = sorted(set(reward_scales or {}) - set(REWARD_SCALES))
        if unknown:
            raise ValueError(f"{type(self).__name__}: no reward term {', '.join(map(repr, unknown))} (the terms: "
                             f"{', '.join(REWARD_SCALES)})")
        self.reward_scales = {**REWARD_SCALES, **{k: float(v) for k, v in (reward_scales or {}).items()}}
        self.num_envs = int(num_envs)
        self.noise, self.randomize, self.episode_steps = noise, randomize, int(episode_steps)
        self.fixed_command = None if command is None else np.asarray(command, dtype=np.float64).reshape(3)
        robot_builder = novaphy.ModelBuilder()
        robot_builder.add_mjcf(robot or go1_scene())
        _with_foot_sensors(robot_builder)
        builder = novaphy.ModelBuilder()
        builder.precision = getattr(novaphy.Precision, precision)
        builder.replicate(robot_builder, self.num_envs)
        model = self.model = builder.finalize()
        n = self.num_envs
        # Playground's position servos: Kp 35, Kd 0.5 (the Menagerie file's are Kp 100 without damping)
        model.set_parameter("actuator_gain", np.full((n, 12), KP))
        model.set_parameter("actuator_bias", np.tile([0.0, -KP, -KD], (n, 12, 1)))
        # the feet's friction decides their contacts with the shared floor (priority over its)
        self._shape_names = np.array(model.shape_name)[np.asarray(model.shape_world) >= 0].reshape(n, -1)[0]
        priority = np.zeros((n, len(self._shape_names)))
        priority[:, np.isin(self._shape_names, FEET)] = 1
        model.set_parameter("shape_priority", priority)
        self._nominal = {name: world_view(model, getattr(model, name)).copy()
                         for name in ("body_mass", "body_com", "body_inertia", "joint_armature", "joint_frictionloss")}
        self._nominal["shape_mu"] = np.asarray(model.shape_mu)[np.asarray(model.shape_world) >= 0].reshape(n, -1)
        home = list(model.keyframes).index("home")
        self._home_q = np.array(model.keyframe_q)[home].reshape(n, -1)[0]
        self._default = self._home_q[7:]
        # Playground's soft limits: the joint ranges scaled by 0.95
        self._soft_lower = SOFT_LIMIT * world_view(model, model.joint_limit_lower)[0, 6:]
        self._soft_upper = SOFT_LIMIT * world_view(model, model.joint_limit_upper)[0, 6:]
        self._force_lower = world_view(model, model.actuator_force_lower)[0]
        self._force_upper = world_view(model, model.actuator_force_upper)[0]

        self.state = model.state(keyframe="home")
        self.control = model.control(keyframe="home")
        self.solver = novaphy.solvers.SolverFeatherstone(model)
        self.solver.settings.num_threads = threads
        self.pipeline = novaphy.CollisionPipeline(model, num_threads=threads)
        self.contacts = self.pipeline.contacts()
        self._q = world_view(model, self.state.joint_q)
        self._qd = world_view(model, self.state.joint_qd)
        self._body_q = world_view(model, self.state.body_q)
        self._body_qd = world_view(model, self.state.body_qd)
        self._ctrl = world_view(model, self.control.actuator_ctrl)
        self._feet = {kind: [novaphy.sensor_view(model, self.state, f"{foot}_{kind}") for foot in FEET]
                      for kind in ("pos", "linvel", "touch")}

        self.single_observation_space = gymnasium.spaces.Box(-np.inf, np.inf, (48,), np.float32)
        self.single_action_space = gymnasium.spaces.Box(-1.0, 1.0, (12,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._rng = np.random.default_rng()
        self._command = np.zeros((n, 3))
        self._until_command = np.zeros(n, dtype=np.int64)  # control steps until a world's next command
        self._air_time = np.zeros((n, 4))  # each foot's time off the floor, its highest point since and its contact
        self._swing_peak = np.zeros((n, 4))
        self._last_contact = np.zeros((n, 4), dtype=bool)
        self._last_action = np.zeros((n, 12))
        self._steps = np.zeros(n, dtype=np.int64)

    # ---- the task

    def _first_commands(self, count):
        """An episode's first commands: uniform within the amplitudes (none zeroed), as Playground's reset."""
        if self.stand:
            return np.zeros((count, 3))
        if self.fixed_command is not None:
            return np.tile(self.fixed_command, (count, 1))
        return self._rng.uniform(-1.0, 1.0, (count, 3)) * COMMAND_AMPLITUDE

    def _next_commands(self, commands):
        """Playground's new command within an episode: each entry, with chance 1/2, replaced by a uniform one that is
        zeroed unless kept (COMMAND_KEPT)."""
        if self.stand or self.fixed_command is not None:
            return commands
        rng, count = self._rng, len(commands)
        fresh = rng.uniform(-1.0, 1.0, (count, 3)) * COMMAND_AMPLITUDE * (rng.uniform(size=(count, 3)) < COMMAND_KEPT)
        return np.where(rng.uniform(size=(count, 3)) < 0.5, fresh, commands)

    def _command_waits(self, count):
        return np.round(self._rng.exponential(COMMAND_PERIOD, count) / CTRL_DT).astype(np.int64)

    def randomize_worlds(self, worlds):
        """New per-world parameters for `worlds` (ids), as Playground's Go1 randomisation: foot friction U(0.4, 1),
        link masses x U(0.9, 1.1) and the trunk's + U(-1, 1) kg, the trunk's centre of mass + U(-0.05, 0.05) m,
        armature x U(1, 1.05), friction loss x U(0.9, 1.1)."""
        k = len(worlds)
        if k == 0:
            return
        rng = self._rng
        mu = self._nominal["shape_mu"][worlds].copy()
        feet = np.isin(self._shape_names, FEET)
        mu[:, feet] = rng.uniform(0.4, 1.0, (k, 1))
        mass = self._nominal["body_mass"][worlds] * rng.uniform(0.9, 1.1, (k, 13))
        mass[:, 0] += rng.uniform(-1.0, 1.0, k)
        com = self._nominal["body_com"][worlds].copy()
        com[:, 0] += rng.uniform(-0.05, 0.05, (k, 3))
        inertia = self._nominal["body_inertia"][worlds] * (mass / self._nominal["body_mass"][worlds])[..., None]
        self.model.set_parameter("shape_mu", mu, worlds=worlds)
        self.model.set_parameter("body_inertia", inertia, worlds=worlds)
        self.model.set_parameter("body_mass", mass, worlds=worlds)
        self.model.set_parameter("body_com", com, worlds=worlds)
        self.model.set_parameter("joint_armature",
                                 self._nominal["joint_armature"][worlds] * rng.uniform(1.0, 1.05, (k, 18)),
                                 worlds=worlds)
        self.model.set_parameter("joint_frictionloss",
                                 self._nominal["joint_frictionloss"][worlds] * rng.uniform(0.9, 1.1, (k, 18)),
                                 worlds=worlds)

    def _reset_worlds(self, worlds):
        """worlds (ids) at the home keyframe with a new command; where randomize: as Playground's reset, moved by
        U(-0.5, 0.5) m in x and y, turned by U(-3.14, 3.14) about z and the trunk moving at U(-0.5, 0.5) along and
        about each axis, with new parameters"""
        k = len(worlds)
        if k == 0:
            return
        if self.randomize:
            rng = self._rng
            q, qd = self._home_q[None].repeat(k, axis=0), np.zeros((k, self._qd.shape[1]))
            q[:, 0:2] += rng.uniform(-0.5, 0.5, (k, 2))
            half_yaw = rng.uniform(-3.14, 3.14, k) / 2
            turn = np.stack([np.zeros(k), np.zeros(k), np.sin(half_yaw), np.cos(half_yaw)], axis=1)
            q[:, 3:7] = _quat_multiply(q[:, 3:7], turn)
            qd[:, 0:6] = rng.uniform(-0.5, 0.5, (k, 6))
            self._q[worlds] = q
            self._qd[worlds] = qd
            self.model.restart_worlds(self.state, worlds)
            self.randomize_worlds(worlds)
        else:
            self.model.reset_worlds(self.state, worlds, "home")
        self._command[worlds] = self._first_commands(k)
        self._until_command[worlds] = self._command_waits(k)
        self._last_action[worlds] = 0.0
        self._steps[worlds] = 0
        self._ctrl[worlds] = self._default
        self._air_time[worlds] = 0.0
        self._swing_peak[worlds] = 0.0
        self._last_contact[worlds] = False

    def _feet_terms(self):
        """Playground's feet terms at this control step, and the feet's contacts; advances their air times and
        swing peaks (the sensors read the last substep's start, as MuJoCo's sensordata and site positions)"""
        foot_z = np.concatenate([p[:, 2:3] for p in self._feet["pos"]], axis=1)
        speed_xy = np.stack([np.linalg.norm(v[:, :2], axis=1) for v in self._feet["linvel"]], axis=1)
        contact = np.concatenate(self._feet["touch"], axis=1) > 0
        first_contact = (self._air_time > 0) & (contact | self._last_contact)
        self._air_time += CTRL_DT
        self._swing_peak = np.maximum(self._swing_peak, foot_z)
        moving = np.linalg.norm(self._command, axis=1) > 0.01
        terms = {
            "feet_slip": np.sum(speed_xy ** 2 * contact, axis=1) * moving,
            "feet_clearance": np.sum(np.abs(foot_z - MAX_FOOT_HEIGHT) * np.sqrt(speed_xy), axis=1),
            "feet_height": np.sum((self._swing_peak / MAX_FOOT_HEIGHT - 1.0) ** 2 * first_contact, axis=1) * moving,
            "feet_air_time": np.sum((self._air_time - 0.1) * first_contact, axis=1) * moving,
        }
        self._air_time *= ~contact
        self._swing_peak *= ~contact
        self._last_contact = contact
        return terms

    def _trunk(self):
        """The trunk's linear velocity, angular velocity and gravity's direction, in its own frame, every world."""
        quat, trunk_qd = self._body_q[:, 0, 3:7], self._body_qd[:, 0]
        return (_rotate_into(quat, trunk_qd[:, :3]), _rotate_into(quat, trunk_qd[:, 3:6]),
                _rotate_into(quat, np.tile([0.0, 0.0, -1.0], (self.num_envs, 1))))

    def _observe(self, trunk):
        linvel, gyro, gravity = trunk
        joint_pos = self._q[:, 7:] - self._default
        joint_vel = self._qd[:, 6:]
        parts = [linvel, gyro, gravity, joint_pos, joint_vel]
        if self.noise:
            rng = self._rng
            parts = [x + rng.uniform(-1.0, 1.0, x.shape) * NOISE[name]
                     for x, name in zip(parts, ("linvel", "gyro", "gravity", "joint_pos", "joint_vel"))]
        return np.concatenate(parts + [self._last_action, self._command], axis=1).astype(np.float32)

    def _rewards(self, trunk, action, torque):
        local_vel, gyro, _ = trunk
        quat, trunk_qd = self._body_q[:, 0, 3:7], self._body_qd[:, 0]
        # the trunk's z axis in the world (Playground's up vector): its third entry is the world's z in the trunk's
        up = _rotate_into(quat * [-1.0, -1.0, -1.0, 1.0], np.tile([0.0, 0.0, 1.0], (self.num_envs, 1)))
        q, qd = self._q[:, 7:], self._qd[:, 6:]
        cmd = self._command
        terms = {
            "tracking_lin_vel": np.exp(-np.sum((cmd[:, :2] - local_vel[:, :2]) ** 2, axis=1) / TRACKING_SIGMA),
            "tracking_ang_vel": np.exp(-(cmd[:, 2] - gyro[:, 2]) ** 2 / TRACKING_SIGMA),
            "lin_vel_z": trunk_qd[:, 2] ** 2,
            "ang_vel_xy": np.sum(trunk_qd[:, 3:5] ** 2, axis=1),
            "orientation": np.sum(up[:, :2] ** 2, axis=1),
            "dof_pos_limits": np.sum(np.clip(self._soft_lower - q, 0, None) + np.clip(q - self._soft_upper, 0, None),
                                     axis=1),
            "pose": np.exp(-np.sum((q - self._default) ** 2 * POSE_WEIGHTS, axis=1)),
            "stand_still": np.sum(np.abs(q - self._default), axis=1) * (np.linalg.norm(cmd, axis=1) < 0.01),
            "torques": np.sqrt(np.sum(torque ** 2, axis=1)) + np.sum(np.abs(torque), axis=1),
            "action_rate": np.sum((action - self._last_action) ** 2, axis=1),
            "energy": np.sum(np.abs(qd * torque), axis=1),
            **self._feet_terms(),
        }
        return terms, up

    # ---- the Gymnasium interface

    def reset(self, *, seed=None, options=None):
        """Every world at the start (options={"worlds": mask or ids}: only those); returns (observations, info)."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        worlds = np.arange(self.num_envs)
        if options and "worlds" in options:
            given = np.asarray(options["worlds"])
            worlds = np.flatnonzero(given) if given.dtype == bool else given.astype(np.int64)
        self._reset_worlds(worlds)
        return self._observe(self._trunk()), {}

    def _checked(self, actions):
        try:
            a = np.asarray(actions)
        except Exception as e:
            raise TypeError(f"{type(self).__name__}.step: actions must be an array of numbers: {e}") from None
        if a.dtype.kind not in "fiu":
            raise TypeError(f"{type(self).__name__}.step: actions must be numbers, got an array of dtype {a.dtype}")
        if a.shape != (self.num_envs, 12):
            raise ValueError(f"{type(self).__name__}.step: actions have shape {a.shape}, expected ({self.num_envs}, 12)")
        bad = ~np.isfinite(a)
        if bad.any():
            w, k = np.argwhere(bad)[0]
            raise ValueError(f"{type(self).__name__}.step: actions[{w}, {k}] is not finite: {a[w, k]}")
        return a.astype(np.float64)

    def step(self, actions):
        """One control step of every world: (observations, rewards, terminated, truncated, info); info["reward_terms"]
        holds each reward term as it enters the reward (times its scale and the control step, before the clip)."""
        action = np.clip(self._checked(actions), -1.0, 1.0)
        self._ctrl[:] = self._default + ACTION_SCALE * action
        novaphy.simulate(self.pipeline, self.solver, self.state, self.control, self.contacts,
                         int(round(CTRL_DT / SIM_DT)), SIM_DT)
        # the servos' forces at the step's end (MuJoCo's actuator_force after its last substep)
        torque = np.clip(KP * (self._ctrl - self._q[:, 7:]) - KD * self._qd[:, 6:], self._force_lower,
                         self._force_upper)
        trunk = self._trunk()
        terms, up = self._rewards(trunk, action, torque)
        terminated = up[:, 2] < 0.0
        terms["termination"] = terminated.astype(np.float64)
        scaled = {name: self.reward_scales[name] * value * CTRL_DT for name, value in terms.items()}
        reward = np.clip(sum(scaled.values()), 0.0, 10000.0).astype(np.float32)
        self._last_action = action
        self._steps += 1
        self._until_command -= 1
        due = np.flatnonzero(self._until_command <= 0)
        if len(due):
            self._command[due] = self._next_commands(self._command[due])
            self._until_command[due] = self._command_waits(len(due))
        truncated = (self._steps >= self.episode_steps) & ~terminated
        observation = self._observe(trunk)
        info = {"reward_terms": scaled}
        done = np.flatnonzero(terminated | truncated)
        if len(done):
            info["final_obs"] = observation.copy()
            info["_final_obs"] = terminated | truncated
            self._reset_worlds(done)
            observation = self._observe(self._trunk())
        return observation, reward, terminated, truncated, info


class Go1Stand(Go1Joystick):
    """num_envs Go1 worlds standing in their home pose: Go1Joystick with a zero command."""

    stand = True


gymnasium.register("NovaPhy/Go1Joystick-v0", vector_entry_point="novaphy.envs:Go1Joystick")
gymnasium.register("NovaPhy/Go1Stand-v0", vector_entry_point="novaphy.envs:Go1Stand")
