"""Solvers: novaphy.solvers.SolverFeatherstone(model, *, angular_damping=0.05, ...)."""

from ._novaphy import DivergencePolicy, JointSupportMatrix, SolverFeatherstone, SolverFeatherstoneSettings

__all__ = ["DivergencePolicy", "JointSupportMatrix", "SolverFeatherstone", "SolverFeatherstoneSettings"]
