"""novaphy.viewer: GIFs of the demos with the bodies visible, PNG frames and time-series plots."""

import os
import sys

import numpy as np
import pytest
from PIL import Image

import novaphy
import novaphy.viewer

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "bindings", "python", "demos",
                                                "multibody_demo")))

import demo_100_robots  # noqa: E402
import demo_wrecking_ball  # noqa: E402


def body_pixels(image):
    """Pixels close to one of the body colours."""
    rgb = np.asarray(image.convert("RGB"), dtype=int)
    count = 0
    for color in novaphy.viewer.BODY_COLORS:
        target = np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)])
        count += int(np.sum(np.abs(rgb - target).sum(axis=2) < 40))
    return count


def frames_of(path):
    gif = Image.open(path)
    frames = []
    for k in range(gif.n_frames):
        gif.seek(k)
        frames.append(gif.convert("RGB"))
    return frames


def test_wrecking_ball_gif_shows_the_ball_and_the_tower(tmp_path):
    path = str(tmp_path / "wrecking_ball.gif")
    demo_wrecking_ball.run(720, render=path, frames=12)
    frames = frames_of(path)
    assert len(frames) == 13
    for frame in frames:
        assert body_pixels(frame) > 200  # ball, chain and boxes drawn in every frame
    first, last = np.asarray(frames[0], dtype=int), np.asarray(frames[-1], dtype=int)
    assert np.abs(first - last).sum(axis=2).astype(bool).sum() > 1000  # the tower fell


def test_hundred_robots_gif_shows_every_robot(tmp_path):
    path = str(tmp_path / "robots.gif")
    demo_100_robots.run(20, render=path, frames=2)
    frames = frames_of(path)
    assert len(frames) == 3
    for frame in frames:
        assert body_pixels(frame) > 1000  # about a dozen pixels for each of the 100 robots


def test_png_frame_and_recorder(tmp_path):
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    for k, add in enumerate(["box", "sphere", "capsule"]):
        body = builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1), xform=novaphy.Transform([k - 1.0, 0.5, 0.0]))
        if add == "box":
            builder.add_shape_box(body, [0.2, 0.2, 0.2])
        elif add == "sphere":
            builder.add_shape_sphere(body, 0.2)
        else:
            builder.add_shape_capsule(body, 0.1, 0.2)
    model = builder.finalize()
    recorder = novaphy.viewer.Recorder(model, every=2)
    state = model.state()
    for _ in range(5):
        recorder.record(state)
    assert len(recorder.frames) == 3
    path = recorder.save_png(str(tmp_path / "frame.png"))
    image = Image.open(path)
    assert image.size == (400, 400)
    assert body_pixels(image) > 1000


def test_plot_series(tmp_path):
    t = np.linspace(0, 1, 50)
    path = novaphy.viewer.plot_series(t, {"q0": np.sin(t), "q1": np.cos(t)}, str(tmp_path / "q.png"), ylabel="rad")
    image = np.asarray(Image.open(path).convert("RGB"), dtype=int)
    assert (np.abs(image - 255).sum(axis=2) > 30).sum() > 2000  # axes, lines and labels were drawn


def test_gif_needs_frames(tmp_path):
    builder = novaphy.ModelBuilder()
    builder.add_body(novaphy.RigidBody())
    recorder = novaphy.viewer.Recorder(builder.finalize())
    with pytest.raises(ValueError, match="no frames to render"):
        recorder.save_gif(str(tmp_path / "empty.gif"))


def test_chosen_worlds_side_by_side(tmp_path):
    robot = novaphy.ModelBuilder()
    body = robot.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1), xform=novaphy.Transform([0.0, 0.5, 0.0]))
    robot.add_shape_box(body, [0.2, 0.2, 0.2])
    builder = novaphy.ModelBuilder()
    builder.add_ground_plane(0.0)
    builder.replicate(robot, 4)  # four worlds in one place
    model = builder.finalize()
    state = model.state()
    frames, drawn = novaphy.viewer.arrange_worlds(model, [np.asarray(state.body_q)], [3, 1])
    np.testing.assert_array_equal(drawn, [False, True, False, True])
    across = novaphy.viewer.display_basis(model.gravity)[0]
    # world 3 first, world 1 next to it, 0.5 m apart (a world of one body has no width)
    assert frames[0][3, :3] @ across == pytest.approx(0.0)
    assert frames[0][1, :3] @ across == pytest.approx(0.5)
    one = np.asarray(Image.open(novaphy.viewer.render_png(model, state.body_q, str(tmp_path / "one.png"),
                                                          worlds=[0])).convert("RGB"))
    two = np.asarray(Image.open(novaphy.viewer.render_png(model, state.body_q, str(tmp_path / "two.png"),
                                                          worlds=[0, 2])).convert("RGB"))
    assert body_pixels(Image.fromarray(two)) > 1.5 * body_pixels(Image.fromarray(one))
    recorder = novaphy.viewer.Recorder(model, worlds=[0, 1, 2])
    recorder.record(state)
    recorder.save_gif(str(tmp_path / "three.gif"))
    with pytest.raises(ValueError, match="world 7 is not a world of the model"):
        novaphy.viewer.render_png(model, state.body_q, str(tmp_path / "bad.png"), worlds=[7])
