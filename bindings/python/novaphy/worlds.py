"""Per-world views: a State, Control or Model array as (world_count, n, ...) without copying.

    q = novaphy.world_view(model, state.joint_q)     # shape (world_count, coords per world)
    q[3, 0] = 0.5                                     # writes world 3's first coordinate in the engine

    gyro = novaphy.sensor_view(model, state, "gyro")  # shape (world_count, 3): that sensor in every world

Valid for the arrays whose rows are bodies, joints, coordinates, dofs, articulations, actuators, sensors (and their
values) or (where no shape is static) shapes, when every world has the same layout and its entries are contiguous, as ModelBuilder.replicate
makes them; anything else (contacts, meshes, tendons, keyframes, ...) raises ValueError.
"""

import numpy as np

from . import _novaphy
from ._novaphy import world_layout


def _owner(array):
    """The State, Control, Model or Contacts whose buffer the array views, or None."""
    base = array
    while base is not None:
        if isinstance(base, (_novaphy.State, _novaphy.Control, _novaphy.Model, _novaphy.Contacts)):
            return base
        base = getattr(base, "base", None)
    return None


def _rows_per_world(model, layout, rows):
    """Entries per world of a field whose rows are `rows` (a count's name), or None where they are not per world."""
    per_world = {
        "body_count": layout.body_count,
        "joint_coord_count": layout.joint_coord_count,
        "joint_dof_count": layout.joint_dof_count,
        "articulation_count": layout.articulation_count,
        "actuator_count": layout.actuator_count,
        "world_count": 1,
    }
    if model.joint_count % model.world_count == 0:
        per_world["joint_count"] = model.joint_count // model.world_count
    if rows in ("sensor_count", "sensor_value_count"):
        worlds = np.asarray(model.sensor_world)
        if rows == "sensor_value_count":
            worlds = np.repeat(worlds, np.diff(np.asarray(model.sensor_start)))
        counts = np.bincount(worlds, minlength=model.world_count)
        return int(counts[0]) if len(worlds) == 0 or (counts == counts[0]).all() else None
    if rows == "shape_count":
        worlds = np.asarray(model.shape_world)
        counts = np.bincount(worlds[worlds >= 0], minlength=model.world_count)
        alike = (worlds >= 0).all() and (np.diff(worlds) >= 0).all() and (counts == counts[0]).all()
        return int(counts[0]) if alike else None
    return per_world.get(rows)


def _field_name(owner, array):
    """The name of the owner's field the array views."""
    for name in _novaphy._field_rows[type(owner).__name__]:
        field = getattr(owner, name)
        if field.__array_interface__["data"][0] == array.__array_interface__["data"][0] and field.shape == array.shape:
            return name
    return None


def world_view(model, array):
    """The array, whose first axis runs over bodies, joints, coordinates, dofs, articulations, actuators or shapes
    of the model, as (world_count, entries per world, ...) over the same memory."""
    if not isinstance(model, _novaphy.Model):
        raise TypeError(f"world_view: model must be a novaphy.Model, got {type(model).__name__}")
    if not isinstance(array, np.ndarray):
        raise TypeError(f"world_view: array must be a numpy array (a State, Control or Model field), got "
                        f"{type(array).__name__}")
    world_count = model.world_count
    try:
        layout = world_layout(model)
    except ValueError as e:
        raise ValueError(f"world_view: the worlds of this model differ in layout (build them with replicate): {e}")
    owner = _owner(array)
    if isinstance(owner, _novaphy.Contacts):
        raise ValueError("world_view: contact arrays are not per world (a contact's world is its shapes': "
                         "model.shape_world[contacts.contact_shape_a], or of shape b where a is static)")
    n = array.shape[0] if array.ndim > 0 else 0
    if owner is not None:
        name = _field_name(owner, array)
        rows = _novaphy._field_rows[type(owner).__name__].get(name)
        if name is None:
            raise ValueError(f"world_view: the array is a part of a {type(owner).__name__} field, not a whole field")
        if owner.model_id != model.model_id:
            raise ValueError(f"world_view: {type(owner).__name__}.{name} belongs to another model")
        per_world = _rows_per_world(model, layout, rows)
        if per_world is None:
            raise ValueError(f"world_view: {type(owner).__name__}.{name} is not per world (its rows count {rows}"
                             + (", and some shapes are static or the worlds' shapes differ" if rows == "shape_count"
                                else "") + ")")
    else:
        counts = {k: v for k in ("body_count", "joint_count", "joint_coord_count", "joint_dof_count",
                                 "articulation_count", "actuator_count", "shape_count")
                  if (v := _rows_per_world(model, layout, k)) is not None}
        per_world = next((v for v in counts.values() if v * world_count == n), None)
        if per_world is None:
            raise ValueError(f"world_view: {n} rows are none of the model's per-world counts times {world_count} "
                             f"worlds ({', '.join(f'{k} {v * world_count}' for k, v in counts.items())})")
    if per_world * world_count != n:
        raise ValueError(f"world_view: {n} entries do not split into {world_count} worlds of {per_world}")
    view = array.reshape((world_count, per_world) + array.shape[1:])
    if n > 0 and not np.shares_memory(view, array):
        raise ValueError("world_view: the array is not contiguous")
    return view


def sensor_view(model, state, name):
    """The values of the sensor called `name` in every world, as (world_count, its values) over state.sensor_data
    (no copy): each world's sensor of that name, the worlds laid out alike (ModelBuilder.replicate)."""
    names = list(model.sensor_name)
    per_world = len(names) // model.world_count if model.world_count else 0
    first = [s for s in range(per_world) if names[s] == name]
    if not first:
        raise KeyError(f"sensor_view: no sensor '{name}' in world 0 (its sensors: {', '.join(names[:per_world])})")
    if len(first) > 1:
        raise KeyError(f"sensor_view: {len(first)} sensors of world 0 are called '{name}'")
    values = world_view(model, state.sensor_data)
    start = np.asarray(model.sensor_start)
    s = first[0]
    return values[:, start[s] : start[s + 1]]
