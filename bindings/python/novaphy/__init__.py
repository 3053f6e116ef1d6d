"""NovaPhy: batched articulated-body physics in reduced coordinates (Featherstone's algorithms).

novaphy.mpi (worlds sharded over MPI ranks) needs mpi4py and is imported on its own.
"""

import numpy as np

from . import _novaphy, solvers
from ._arguments import name_the_culprits
from .worlds import sensor_view, world_view

name_the_culprits(_novaphy)
from ._novaphy import (
    CollisionFilter,
    FrictionRule,
    CollisionPipeline,
    ForwardDynamics,
    ContactOverflow,
    Contacts,
    Control,
    Error,
    Joint,
    JointDofConfig,
    JointType,
    Model,
    MujocoImport,
    ModelBuilder,
    Precision,
    RigidBody,
    SensorType,
    ShapeType,
    State,
    TendonPathElement,
    TendonPathKind,
    Transform,
    WorldLayout,
    WorldRange,
    build_worlds,
    eval_bias_forces,
    eval_control_force,
    eval_energy,
    eval_fk,
    eval_forward_dynamics,
    eval_inverse_dynamics,
    eval_mass_matrix,
    forward_dynamics,
    forward_kinematics,
    inverse_dynamics,
    mass_matrix_crba,
    shard_range,
    simulate,
    world_layout,
)

__all__ = [
    "CollisionPipeline",
    "CollisionFilter",
    "FrictionRule",
    "ForwardDynamics",
    "ContactOverflow",
    "Contacts",
    "Control",
    "Error",
    "Joint",
    "JointDofConfig",
    "JointType",
    "Model",
    "MujocoImport",
    "from_mujoco",
    "ModelBuilder",
    "Precision",
    "RigidBody",
    "SensorType",
    "ShapeType",
    "State",
    "TendonPathElement",
    "TendonPathKind",
    "Transform",
    "WorldLayout",
    "WorldRange",
    "build_worlds",
    "eval_bias_forces",
    "eval_control_force",
    "eval_energy",
    "eval_fk",
    "eval_forward_dynamics",
    "eval_inverse_dynamics",
    "eval_mass_matrix",
    "forward_dynamics",
    "forward_kinematics",
    "inverse_dynamics",
    "mass_matrix_crba",
    "sensor_view",
    "shard_range",
    "simulate",
    "solvers",
    "world_layout",
    "world_view",
]


def from_mujoco(model, worlds=1, precision=Precision.Float64):
    """A Model of `worlds` worlds, each the compiled mujoco.MjModel `model` (of the user's MuJoCo, 3.x or 4.x):
    the model add_mjcf builds from the same file. Warns about what is not modelled, as add_mjcf does;
    ModelBuilder.add_mujoco_model gives the state maps (qpos / qvel <-> joint_q / joint_qd)."""
    if isinstance(worlds, bool) or not isinstance(worlds, (int, np.integer)):
        raise TypeError(f"from_mujoco(): worlds={worlds!r} must be an int, got {type(worlds).__name__}")
    if not 1 <= worlds <= 2**31 - 1:
        raise ValueError(f"from_mujoco(): worlds={worlds} must be in [1, 2147483647]")
    if not isinstance(precision, Precision):
        raise TypeError(f"from_mujoco(): precision={precision!r} must be a Precision (Precision.Float64, "
                        f"Precision.Float32), got {type(precision).__name__}")
    robot = ModelBuilder()
    robot.add_mujoco_model(model)
    batch = ModelBuilder()
    batch.precision = precision
    batch.replicate(robot, worlds)
    return batch.finalize()
