"""Each demo, shortened, reaches its physical outcome."""

import os
import sys

import numpy as np
import pytest

DEMOS = os.path.join(os.path.dirname(__file__), "..", "..", "bindings", "python", "demos", "multibody_demo")
sys.path.insert(0, os.path.abspath(DEMOS))

import demo_100_robots  # noqa: E402
import demo_motor_arm  # noqa: E402
import demo_newtons_cradle_pendulum  # noqa: E402
import demo_rope  # noqa: E402
import demo_seesaw  # noqa: E402
import demo_wrecking_ball  # noqa: E402


def test_newtons_cradle_passes_the_momentum_to_the_last_ball():
    s = demo_newtons_cradle_pendulum.run(1500)
    assert s["last_ball_peak_angle"] > 0.9 * s["release_angle"]
    assert s["first_ball_peak_after_impact"] < 0.1 * s["release_angle"]


def test_rope_swings_down_and_stays_attached():
    s = demo_rope.run(480)
    assert s["lowest_tip_height"] < demo_rope.PIVOT[1] - 1.2  # the 1.5 m chain swung down
    assert s["worst_joint_gap"] < 1e-12


def test_wrecking_ball_knocks_the_tower_down():
    s = demo_wrecking_ball.run(720)
    assert s["boxes_moved"] >= s["boxes"] // 2
    # from six boxes high to at most three (which boxes end on which is chaotic: a sweep more or less moves it)
    assert s["tower_height_before"] > 5.9 * 2 * demo_wrecking_ball.BOX
    assert s["tower_height_after"] < 3.5 * 2 * demo_wrecking_ball.BOX


def test_wrecking_ball_tower_stands_until_hit():
    sim, boxes = demo_wrecking_ball.build()
    start = sim.state.body_q[boxes, :3].copy()
    for _ in range(60):  # a quarter second: the ball is still high in its swing
        sim.step()
    assert np.abs(sim.state.body_q[boxes, :3] - start).max() < 0.005


def test_seesaw_tilts_towards_the_box():
    s = demo_seesaw.run(300)
    assert s["plank_angle"] < -0.3  # the +x end went down
    assert s["plank_angle"] > -demo_seesaw.LIMIT - 0.01  # held by its limit


def test_motor_arm_reaches_its_target_and_sweeps_the_boxes():
    s = demo_motor_arm.run(480)
    assert s["arm_angle"] == pytest.approx(s["target"], rel=0.01)
    assert s["boxes_moved"] >= 2


def test_robots_stay_upright():
    s = demo_100_robots.run(200, side=4)
    assert s["upright"] == s["robots"] == 16
