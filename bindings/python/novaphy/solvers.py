"""Solvers over one Model: SolverFeatherstone (reduced coordinates, the default for articulated robots),
SolverSemiImplicit (maximal coordinates, sequential-impulse PGS rows) and SolverXPBD (maximal coordinates,
position-level constraints with compliance). solver.joint_support() says which joint types each enforces."""

from ._novaphy import (
    DivergencePolicy,
    JointSupportMatrix,
    SolverFeatherstone,
    SolverFeatherstoneSettings,
    SolverSemiImplicit,
    SolverSemiImplicitSettings,
    SolverXPBD,
    SolverXPBDSettings,
)

__all__ = [
    "DivergencePolicy",
    "JointSupportMatrix",
    "SolverFeatherstone",
    "SolverFeatherstoneSettings",
    "SolverSemiImplicit",
    "SolverSemiImplicitSettings",
    "SolverXPBD",
    "SolverXPBDSettings",
]
