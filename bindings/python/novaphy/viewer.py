"""Headless rendering of a model's shapes to PNG frames and animated GIFs, and time-series plots.

    recorder = novaphy.viewer.Recorder(model, every=4)
    for _ in range(steps):
        ...step...
        recorder.record(state)
    recorder.save_gif("run.gif")

Boxes, spheres, capsules and planes are drawn from ``body_q`` with matplotlib (Agg, no display needed);
the view looks along the horizontal with the model's up axis (against gravity) pointing up. ``worlds=[...]`` (on
Recorder, render_png and save_gif) draws only those worlds of a model of many, side by side across the view in the
order given (``arrange_worlds``), with the static shapes (a shared floor) under them all.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402
from PIL import Image  # noqa: E402

from ._novaphy import ShapeType  # noqa: E402

BODY_COLORS = ["#e4572e", "#17bebb", "#ffc914", "#76b041", "#2e86ab", "#a23b72", "#f18f01", "#c73e1d"]
STATIC_COLOR = "#b8b8b8"


def quat_to_matrix(q):
    """Rotation matrix of a quaternion [x, y, z, w]."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def compose(a, b):
    """Transform a * b of two [p, q] transforms, as (position, rotation matrix)."""
    Ra = quat_to_matrix(a[3:])
    return a[:3] + Ra @ b[:3], Ra @ quat_to_matrix(b[3:])


def display_basis(gravity):
    """Rows map world coordinates to display coordinates with the up axis (against gravity) as display z."""
    g = np.asarray(gravity, dtype=float)
    up = -g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else np.array([0.0, 0.0, 1.0])
    side = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = side - up * side.dot(up)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(up, e1), up])


def box_faces(center, R, half):
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    corners = center + (signs * half) @ R.T
    quads = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]]
    return [corners[q] for q in quads]


def revolved_faces(center, R, profile, segments=8):
    """Quads of a surface of revolution about local Y: profile is a list of (y, radius)."""
    angles = np.linspace(0, 2 * np.pi, segments + 1)
    rings = [
        center + np.stack([r * np.cos(angles), np.full_like(angles, y), r * np.sin(angles)], 1) @ R.T
        for y, r in profile
    ]
    faces = []
    for a, b in zip(rings[:-1], rings[1:]):
        for k in range(segments):
            faces.append(np.array([a[k], a[k + 1], b[k + 1], b[k]]))
    return faces


def hull_faces(model, mesh, center, R):
    """The polygons of mesh `mesh`'s convex hull (model.mesh_*), placed at center and turned by R."""
    first = model.mesh_vertex_start[mesh]
    vertices = center + model.mesh_vertex[first : model.mesh_vertex_start[mesh + 1]] @ R.T
    starts = model.mesh_corner_start
    return [
        vertices[model.mesh_corner[starts[f] : starts[f + 1]]]
        for f in range(model.mesh_face_start[mesh], model.mesh_face_start[mesh + 1])
    ]


def sphere_profile(radius, rings=4):
    t = np.linspace(-np.pi / 2, np.pi / 2, rings + 1)
    return [(radius * np.sin(a), radius * np.cos(a)) for a in t]


def capsule_profile(radius, half_height, rings=2):
    t = np.linspace(0, np.pi / 2, rings + 1)
    bottom = [(-half_height - radius * np.cos(a), radius * np.sin(a)) for a in t]
    top = [(half_height + radius * np.sin(a), radius * np.cos(a)) for a in t]
    return bottom + top


def arrange_worlds(model, frames, worlds):
    """Frames (body_q arrays) with worlds `worlds` (ids, in the order to lay them out) moved side by side across the
    view, each world's centre `spacing` apart along the display's horizontal axis (spacing: the widest world's extent
    plus 0.5 m), and the mask of the bodies to draw (those worlds'): (frames, drawn)."""
    body_world = np.asarray(model.body_world)
    worlds = [int(w) for w in worlds]
    for w in worlds:
        if not 0 <= w < model.world_count:
            raise ValueError(f"viewer: world {w} is not a world of the model (0 .. {model.world_count - 1})")
    if len(set(worlds)) != len(worlds):
        raise ValueError(f"viewer: worlds {worlds} name a world twice")
    drawn = np.isin(body_world, worlds)
    across = display_basis(model.gravity)[0]  # the display's horizontal axis, in the world
    first = np.asarray(frames[0])[:, :3] @ across
    centre = {w: first[body_world == w].mean() if (body_world == w).any() else 0.0 for w in worlds}
    extent = max((np.ptp(first[body_world == w]) if (body_world == w).any() else 0.0) for w in worlds)
    spacing = extent + 0.5
    shift = np.zeros((model.body_count, 3))
    for slot, w in enumerate(worlds):
        shift[body_world == w] = (slot * spacing - centre[w]) * across
    arranged = []
    for f in frames:
        f = np.array(f, copy=True)
        f[:, :3] += shift
        arranged.append(f)
    return arranged, drawn


class Recorder:
    """Keeps a copy of body_q every `every` calls to record(); renders them as PNG frames or a GIF (of worlds
    `worlds` only, side by side, where given)."""

    def __init__(self, model, every=1, worlds=None):
        self.model = model
        self.every = max(1, int(every))
        self.worlds = worlds
        self.frames = []
        self._calls = 0

    def record(self, state):
        if self._calls % self.every == 0:
            self.frames.append(np.array(state.body_q, copy=True))
        self._calls += 1

    def save_png(self, path, frame=-1, **view):
        frames, drawn = self._arranged()
        render_png(self.model, frames[frame], path, bounds=scene_bounds(self.model, frames, drawn), drawn=drawn,
                   **view)
        return path

    def save_gif(self, path, fps=20, **view):
        save_gif(self.model, self.frames, path, fps=fps, worlds=self.worlds, **view)
        return path

    def bounds(self):
        frames, drawn = self._arranged()
        return scene_bounds(self.model, frames, drawn)

    def _arranged(self):
        if self.worlds is None:
            return self.frames, None
        return arrange_worlds(self.model, self.frames, self.worlds)


def joint_segments(model, body_q, drawn=None):
    """World segments from each joint's anchor on its parent (or the world) to its child's origin (the joints of the
    drawn bodies only, where a mask is given)."""
    segments = []
    for j in range(model.joint_count):
        if drawn is not None and not drawn[model.joint_child[j]]:
            continue
        parent = model.joint_parent[j]
        X_p = model.joint_X_p[j]
        anchor = compose(body_q[parent], X_p)[0] if parent >= 0 else X_p[:3]
        child = body_q[model.joint_child[j], :3]
        if np.linalg.norm(child - anchor) > 1e-6 and not (parent < 0 and model.joint_type[j] == 4):
            segments.append((anchor, child))
    return segments


def scene_bounds(model, frames, drawn=None):
    """Centre and half size (display frame) of where the (drawn) bodies and joints mostly are, at least 1 m across."""
    basis = display_basis(model.gravity)
    points = []
    for f in frames:
        points.append(f[:, :3] if drawn is None else f[drawn, :3])
        points += [np.array(seg) for seg in joint_segments(model, f, drawn)]
    points = np.concatenate(points) @ basis.T if points else np.zeros((1, 3))
    # bodies flung far away leave the view rather than shrink the scene
    lo, hi = np.percentile(points, 2, axis=0) - 0.3, np.percentile(points, 98, axis=0) + 0.3
    return (lo + hi) / 2, max((hi - lo).max() / 2, 0.5)


def shape_faces(model, body_q, basis, bounds, drawn=None):
    """Polygons (display frame) and their colours for every shape (of the drawn bodies, and every static one) at the
    poses body_q: (planes, bodies)."""
    planes, bodies = ([], []), ([], [])
    center, half = bounds
    for s in range(model.shape_count):
        body = model.shape_body[s]
        if drawn is not None and body >= 0 and not drawn[body]:
            continue
        local = model.shape_transform[s]
        if body >= 0:
            p, R = compose(body_q[body], local)
            color = BODY_COLORS[body % len(BODY_COLORS)]
        else:
            p, R = local[:3].copy(), quat_to_matrix(local[3:])
            color = STATIC_COLOR
        p, R = basis @ p, basis @ R
        scale = model.shape_scale[s]
        kind = ShapeType(model.shape_type[s])
        target = bodies
        if kind == ShapeType.Box:
            faces = box_faces(p, R, scale)
        elif kind == ShapeType.Sphere:
            faces = revolved_faces(p, R, sphere_profile(scale[0]))
        elif kind == ShapeType.Capsule:
            faces = revolved_faces(p, R, capsule_profile(scale[0], scale[1]))
        elif kind == ShapeType.Cylinder:
            faces = revolved_faces(p, R, [(-scale[1], 0.0), (-scale[1], scale[0]), (scale[1], scale[0]), (scale[1], 0.0)])
        elif kind == ShapeType.Ellipsoid:
            faces = revolved_faces(p, R @ np.diag(scale), sphere_profile(1.0))
        elif kind == ShapeType.Mesh:
            faces = hull_faces(model, model.shape_mesh[s], p, R)
        else:
            # a square of the plane under the scene, centred below the scene's centre
            u, v = R[:, 0], R[:, 2]
            c = p + u * u.dot(center - p) + v * v.dot(center - p)
            faces = [np.array([c + half * (su * u + sv * v) for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))])]
            target = planes
        target[0].extend(faces)
        target[1].extend([color] * len(faces))
    return planes, bodies


def draw(ax, model, body_q, bounds, elevation=20.0, azimuth=-60.0, drawn=None):
    basis = display_basis(model.gravity)
    planes, bodies = shape_faces(model, body_q, basis, bounds, drawn)
    # planes first, then the bodies over them (depth sorting happens within each collection only)
    ax.computed_zorder = False
    ax.add_collection3d(Poly3DCollection(planes[0], facecolors=planes[1], edgecolors="none", zorder=1))
    ax.add_collection3d(
        Poly3DCollection(bodies[0], facecolors=bodies[1], edgecolors="#333333", linewidths=0.2, zorder=2)
    )
    segments = [[basis @ a, basis @ b] for a, b in joint_segments(model, body_q, drawn)]
    if segments:
        ax.add_collection3d(Line3DCollection(segments, colors="#444444", linewidths=1.0, zorder=3))
    center, half = bounds
    ax.set_xlim(center[0] - half, center[0] + half)
    ax.set_ylim(center[1] - half, center[1] + half)
    ax.set_zlim(center[2] - half, center[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elevation, azim=azimuth)
    ax.set_axis_off()


def render_image(model, body_q, bounds, size=(400, 400), **view):
    """One frame as an RGB array of shape (height, width, 3) (view: elevation, azimuth, drawn)."""
    dpi = 80
    fig = plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    ax = fig.add_axes([0, 0, 1, 1], projection="3d")
    draw(ax, model, np.asarray(body_q), bounds, **view)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    return image


def render_png(model, body_q, path, bounds=None, worlds=None, **view):
    """One frame as a PNG (of worlds `worlds` only, side by side, where given)."""
    frames, drawn = [np.asarray(body_q)], view.pop("drawn", None)
    if worlds is not None:
        frames, drawn = arrange_worlds(model, frames, worlds)
    bounds = bounds or scene_bounds(model, frames, drawn)
    Image.fromarray(render_image(model, frames[0], bounds, drawn=drawn, **view)).save(path)
    return path


def save_gif(model, frames, path, fps=20, worlds=None, **view):
    """An animated GIF of the recorded body_q frames, all in one fixed view (of worlds `worlds` only, side by
    side, where given)."""
    if len(frames) == 0:
        raise ValueError("no frames to render: record some states first")
    drawn = None
    if worlds is not None:
        frames, drawn = arrange_worlds(model, frames, worlds)
    view["drawn"] = drawn
    bounds = scene_bounds(model, frames, drawn)
    images = [Image.fromarray(render_image(model, f, bounds, **view)) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
    return path


def plot_series(times, series, path, ylabel="", title=""):
    """Line plot of named time series (dict name -> values over times) saved as PNG."""
    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    for name, values in series.items():
        ax.plot(times, values, label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path
