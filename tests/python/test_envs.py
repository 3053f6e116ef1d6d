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
