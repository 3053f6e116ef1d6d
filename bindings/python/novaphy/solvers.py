"""Solvers: novaphy.solvers.SolverFeatherstone(model, *, angular_damping=0.05, ...)."""

from ._novaphy import JointSupportMatrix, SolverFeatherstone, SolverFeatherstoneSettings

__all__ = ["JointSupportMatrix", "SolverFeatherstone", "SolverFeatherstoneSettings"]
