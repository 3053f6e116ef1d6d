"""NovaPhy: batched articulated-body physics in reduced coordinates (Featherstone's algorithms).

novaphy.mpi (worlds sharded over MPI ranks) needs mpi4py and is imported on its own.
"""

from . import solvers
from .worlds import world_view
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
    ShapeType,
    State,
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
    "ShapeType",
    "State",
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
    "shard_range",
    "solvers",
    "world_layout",
    "world_view",
]


def from_mujoco(model, worlds=1, precision=Precision.Float64):
    """A Model of `worlds` worlds, each the compiled mujoco.MjModel `model` (of the user's MuJoCo, 3.x or 4.x):
    the model add_mjcf builds from the same file. Warns about what is not modelled, as add_mjcf does;
    ModelBuilder.add_mujoco_model gives the state maps (qpos / qvel <-> joint_q / joint_qd)."""
    robot = ModelBuilder()
    robot.add_mujoco_model(model)
    batch = ModelBuilder(gravity=robot.gravity)
    batch.precision = precision
    batch.replicate(robot, worlds)
    return batch.finalize()
