"""Per-world views: a State, Control or Model array as (world_count, n, ...) without copying.

    q = novaphy.world_view(model, state.joint_q)     # shape (world_count, coords per world)
    q[3, 0] = 0.5                                     # writes world 3's first coordinate in the engine

Valid when every world has the same layout and its entries are contiguous, as ModelBuilder.replicate
makes them; anything else raises ValueError.
"""

import numpy as np


def _uniform(worlds, world_count):
    """True if the per-entry world indices run 0, 0, ..., 1, 1, ... in equal blocks."""
    worlds = np.asarray(worlds)
    if worlds.size == 0:
        return True
    if np.any(worlds < 0) or np.any(np.diff(worlds) < 0):
        return False
    counts = np.bincount(worlds, minlength=world_count)
    return bool(np.all(counts == counts[0]))


def world_view(model, array):
    """The array, whose first axis runs over bodies, joints, coordinates, dofs or shapes of the model, as
    (world_count, entries per world, ...) over the same memory."""
    world_count = model.world_count
    joint_world = model.body_world[model.joint_child]
    coord_world = np.repeat(joint_world, np.diff(model.joint_q_start))
    dof_world = np.repeat(joint_world, np.diff(model.joint_qd_start))
    if not all(_uniform(w, world_count) for w in (model.body_world, joint_world, coord_world, dof_world)):
        raise ValueError("world_view: the worlds of this model differ in layout (build them with replicate)")
    n = array.shape[0]
    if n % world_count != 0:
        raise ValueError(f"world_view: {n} entries do not split into {world_count} worlds")
    view = array.reshape((world_count, n // world_count) + array.shape[1:])
    if not np.shares_memory(view, array):
        raise ValueError("world_view: the array is not contiguous")
    return view
