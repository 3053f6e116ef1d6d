"""novaphy.envs: the Go1 vector environments through gymnasium.make_vec: spaces, observations of a robot at home,
rewards, autoreset, per-world randomisation on reset, and bad actions named."""
import numpy as np
import pytest

import novaphy

gymnasium = pytest.importorskip("gymnasium")
envs = pytest.importorskip("novaphy.envs")

try:
    envs.go1_scene()
except FileNotFoundError:
    pytest.skip("the Menagerie Go1 is not on disk", allow_module_level=True)


def make(name="NovaPhy/Go1Joystick-v0", n=4, **kwargs):
    return gymnasium.make_vec(name, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)


def test_make_vec_gives_a_vector_env_of_the_task_spaces():
    env = make(noise=False, randomize=False, command=[0.5, 0.0, 0.0])
    assert isinstance(env, gymnasium.vector.VectorEnv)
    assert env.observation_space.shape == (4, 48) and env.action_space.shape == (4, 12)
    obs, info = env.reset(seed=1)
    assert obs.shape == (4, 48) and obs.dtype == np.float32
    # at home: at rest, upright (gravity straight down the trunk's z), the joints at the home pose, no last action
    np.testing.assert_allclose(obs[:, 0:6], 0, atol=1e-6)
    np.testing.assert_allclose(obs[:, 6:9], np.tile([0, 0, -1], (4, 1)), atol=1e-5)
    np.testing.assert_allclose(obs[:, 9:21], 0, atol=1e-6)
    np.testing.assert_array_equal(obs[:, 45:], np.tile([0.5, 0, 0], (4, 1)))
    obs, reward, terminated, truncated, info = env.step(np.zeros((4, 12), np.float32))
    assert reward.shape == (4,) and terminated.shape == (4,) and truncated.shape == (4,)
    assert env.observation_space.contains(obs)


def test_a_standing_robot_is_rewarded_and_stays_up():
    env = make("NovaPhy/Go1Stand-v0", noise=False)
    env.reset(seed=2)
    total = np.zeros(4)
    for _ in range(50):
        obs, reward, terminated, truncated, info = env.step(np.zeros((4, 12)))
        assert not terminated.any()
        total += reward
    assert (total > 0).all()
    assert (obs[:, 8] < -0.95).all()  # still upright


def test_worlds_that_end_restart_in_the_same_step():
    env = make(noise=False, randomize=False, episode_steps=3)
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    for k in range(3):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, (4, 12)))
    assert truncated.all() and not terminated.any()
    assert info["_final_obs"].all() and np.abs(info["final_obs"][:, 33:45]).max() > 0  # the ended episode's action
    np.testing.assert_allclose(obs[:, 9:21], 0, atol=1e-6)  # the new episode's first: at home
    assert not obs[:, 33:45].any()
    obs, reward, terminated, truncated, info = env.step(np.zeros((4, 12)))
    assert not truncated.any()


def test_each_reset_gives_the_worlds_their_own_parameters():
    env = make(n=3)
    env.reset(seed=4)
    model = env.unwrapped.model if hasattr(env, "unwrapped") else env.model
    mass = np.asarray(model.body_mass).reshape(3, -1)
    assert len({tuple(m) for m in mass}) == 3
    first = mass.copy()
    env.reset(seed=4)
    np.testing.assert_array_equal(np.asarray(model.body_mass).reshape(3, -1), first)  # the seed decides
    env.reset(options={"worlds": [1]})
    after = np.asarray(model.body_mass).reshape(3, -1)
    np.testing.assert_array_equal(after[[0, 2]], first[[0, 2]])
    assert (after[1] != first[1]).any()


def test_bad_actions_are_named():
    env = make(n=2)
    env.reset(seed=5)
    with pytest.raises(ValueError, match=r"actions have shape \(2, 11\), expected \(2, 12\)"):
        env.step(np.zeros((2, 11)))
    with pytest.raises(TypeError, match="actions must be numbers"):
        env.step(np.full((2, 12), "x"))
    actions = np.zeros((2, 12))
    actions[1, 4] = np.nan
    with pytest.raises(ValueError, match=r"actions\[1, 4\] is not finite"):
        env.step(actions)
    with pytest.raises(ValueError, match="num_envs must be a positive integer"):
        make(n=0)
    with pytest.raises(ValueError, match="no reward term 'feet_lift' \\(the terms: tracking_lin_vel, "):
        make(reward_scales={"feet_lift": 0.0})


def test_reward_scales_replace_playgrounds():
    """The terms scaled to 0 enter the reward as 0; the rest as Playground scales them."""
    runs = []
    for scales in (None, {"feet_clearance": 0.0, "pose": 2.0}):
        env = make(n=2, noise=False, randomize=False, command=[0.5, 0.0, 0.0], reward_scales=scales)
        env.reset(seed=9)
        runs.append(env.step(np.full((2, 12), 0.3))[4]["reward_terms"])
    assert (runs[0]["feet_clearance"] != 0).any() and not runs[1]["feet_clearance"].any()
    np.testing.assert_allclose(runs[1]["pose"], 4 * runs[0]["pose"])
    np.testing.assert_array_equal(runs[1]["tracking_lin_vel"], runs[0]["tracking_lin_vel"])


def test_a_robot_turned_over_is_terminated_and_restarted():
    env = make(noise=False, randomize=False)
    env.reset(seed=6)
    q = novaphy.world_view(env.model, env.state.joint_q)
    q[1, 2] = 1.0
    q[1, 3:7] = [1.0, 0.0, 0.0, 0.0]  # half a turn about x: upside down, a metre up
    obs, reward, terminated, truncated, info = env.step(np.zeros((4, 12)))
    np.testing.assert_array_equal(terminated, [False, True, False, False])
    assert info["final_obs"][1, 8] > 0.9  # gravity along the trunk's +z when it ended
    assert obs[1, 8] < -0.99  # and the new episode's first observation upright


def feet(env, kind, column):
    """(worlds, 4): one column of each foot's sensor of that kind"""
    return np.stack([novaphy.sensor_view(env.model, env.state, f"{foot}_{kind}")[:, column] for foot in envs.FEET], 1)


def test_the_feet_terms_of_a_robot_dropped_onto_its_feet():
    """World 1 starts 0.3 m up: its feet touch nothing (no slip, no air-time or height term) until they land; the
    step they land, Playground's air-time term rewards the time they were off the floor beyond 0.1 s and the height
    term penalises their swing peak (the first reading, the highest they were) against 0.1 m. World 0 stands."""
    env = make(n=2, noise=False, randomize=False, command=[0.5, 0.0, 0.0])
    env.reset(seed=7)
    novaphy.world_view(env.model, env.state.joint_q)[1, 2] += 0.3
    env.model.restart_worlds(env.state, [1])
    for step in range(1, 60):
        _, _, terminated, _, info = env.step(np.zeros((2, 12)))
        z, touch = feet(env, "pos", 2), feet(env, "touch", 0)
        if step == 1:
            peak = z[1].astype(np.float64)
        terms = {name: value / (envs.REWARD_SCALES[name] * envs.CTRL_DT) for name, value in
                 info["reward_terms"].items()}
        if step > 2:
            # world 0 on its feet: the spheres' centres below their radius (0.023 m): pressed into the floor as
            # MuJoCo's soft contacts press them
            assert (touch[0] > 0).all() and (z[0] > 0).all() and (z[0] < 0.023).all()
        landed = touch[1] > 0
        if not landed.any():
            assert terms["feet_air_time"][1] == 0 and terms["feet_height"][1] == 0 and terms["feet_slip"][1] == 0
            continue
        air_time = step * envs.CTRL_DT
        assert 0.2 < air_time < 0.4 and not terminated.any()
        assert terms["feet_air_time"][1] == pytest.approx(landed.sum() * (air_time - 0.1), rel=1e-9)
        assert terms["feet_height"][1] == pytest.approx(np.sum((peak[landed] / envs.MAX_FOOT_HEIGHT - 1) ** 2),
                                                        rel=1e-9)
        break
    else:
        pytest.fail("world 1's feet never landed")


def test_a_randomized_reset_starts_each_world_somewhere_else_moving():
    env = make(n=8, noise=False, randomize=True)
    env.reset(seed=8)
    q = novaphy.world_view(env.model, env.state.joint_q)
    qd = novaphy.world_view(env.model, env.state.joint_qd)
    home = np.array(env.model.keyframe_q)[0].reshape(8, -1)[0]
    assert (np.abs(q[:, 0:2] - home[0:2]) <= 0.5).all() and len({tuple(x) for x in q[:, 0:2]}) == 8
    np.testing.assert_allclose(np.linalg.norm(q[:, 3:7], axis=1), 1.0, atol=1e-6)
    yaw = 2 * np.arctan2(q[:, 5], q[:, 6])
    assert np.ptp(np.unwrap(yaw)) > 1.0  # headings spread over the circle
    assert (np.abs(qd[:, 0:6]) <= 0.5).all() and np.abs(qd[:, 0:6]).min() > 0
    np.testing.assert_array_equal(q[:, 7:], np.tile(home[7:].astype(np.float32), (8, 1)))
    obs, _ = env.reset(seed=8)
    np.testing.assert_allclose(obs[:, 6:9], np.tile([0, 0, -1], (8, 1)), atol=1e-5)  # upright: turned about z only
