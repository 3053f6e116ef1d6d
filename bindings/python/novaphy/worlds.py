"""Per-world views: a State, Control or Model array as (world_count, n, ...) without copying.

    q = novaphy.world_view(model, state.joint_q)     # shape (world_count, coords per world)
    q[3, 0] = 0.5                                     # writes world 3's first coordinate in the engine

Valid when every world has the same layout and its entries are contiguous, as ModelBuilder.replicate
makes them; anything else raises ValueError.
"""

import numpy as np

from ._novaphy import world_layout


def world_view(model, array):
    """The array, whose first axis runs over bodies, joints, coordinates, dofs or shapes of the model, as
    (world_count, entries per world, ...) over the same memory."""
    world_count = model.world_count
    try:
        world_layout(model)
    except ValueError as e:
        raise ValueError(f"world_view: the worlds of this model differ in layout (build them with replicate): {e}")
    n = array.shape[0]
    if n % world_count != 0:
        raise ValueError(f"world_view: {n} entries do not split into {world_count} worlds")
    view = array.reshape((world_count, n // world_count) + array.shape[1:])
    if not np.shares_memory(view, array):
        raise ValueError("world_view: the array is not contiguous")
    return view
