"""Worlds sharded over MPI ranks with mpi4py: the Python counterpart of the C++ ShardedBatch.

    from mpi4py import MPI
    import novaphy
    from novaphy.mpi import ShardedBatch

    def build_world(builder, w):                      # global world w, built alike on every rank
        builder.add_mjcf("quadruped.xml", xform=novaphy.Transform([1.5 * w, 0, 0.3]), static_shapes=False)

    shared = novaphy.ModelBuilder(gravity=[0, 0, -9.81])
    shared.add_plane([0, 0, 1], 0.0)                  # what every world collides with
    batch = ShardedBatch(MPI.COMM_WORLD, 4096, build_world, shared)
    batch.scatter(actions, batch.control.joint_f)     # actions: (4096 * dofs per world,) on the root
    batch.step(0.005)
    q = batch.gather(batch.state.joint_q)             # all worlds on the root, None elsewhere

Each rank owns a contiguous range of the global worlds (novaphy.shard_range), builds only those and
steps them with the local OpenMP engine; per-world arrays travel with MPI collectives. A world steps
exactly as it would in one process (bit-identical). Every method that communicates is collective:
all ranks call it in the same order. An error on one rank is raised (ValueError, naming the rank)
on every rank, so none is left waiting.
"""

import numpy as np
from mpi4py import MPI

from . import _novaphy
from .solvers import SolverFeatherstone


def _agree(comm, error):
    """Raise on every rank when `error` (a message or None) is set on any, with the lowest such rank's."""
    rank, size = comm.Get_rank(), comm.Get_size()
    first = comm.allreduce(size if error is None else rank, op=MPI.MIN)
    if first < size:
        message = comm.bcast(error if rank == first else None, root=first)
        raise ValueError(f"rank {first}: {message}")


def _collectively(comm, f):
    error = None
    try:
        f()
    except Exception as e:  # every rank must learn of it, whatever it is
        error = str(e) or type(e).__name__
    _agree(comm, error)


class ShardedBatch:
    """This rank's share of `world_count` worlds, each built by build_world(builder, world).

    shared: a ModelBuilder with the static shapes every world collides with (no bodies); its gravity
    is the model's. solver_options go to novaphy.solvers.SolverFeatherstone.
    """

    def __init__(self, comm, world_count, build_world, shared=None, **solver_options):
        self.comm = comm
        self.rank, self.size = comm.Get_rank(), comm.Get_size()
        self.world_count = world_count
        self._ranges = []


        def build():
            if world_count < self.size:
                raise ValueError(f"ShardedBatch: world_count must be at least the number of ranks ({self.size}), "
                                 f"got {world_count}")
            self._ranges = [_novaphy.shard_range(world_count, r, self.size) for r in range(self.size)]
            self.model = _novaphy.build_worlds(shared or _novaphy.ModelBuilder(), build_world, self.range)
            self.layout = _novaphy.world_layout(self.model)
            self.state = self.model.state()
            self._next = self.model.state()
            self.control = self.model.control()
            self.pipeline = _novaphy.CollisionPipeline(self.model)
            self.contacts = self.pipeline.contacts()
            self.solver = SolverFeatherstone(self.model, **solver_options)

        _collectively(comm, build)
        layout = self.layout
        mine = (layout.body_count, layout.joint_coord_count, layout.joint_dof_count, layout.articulation_count,
                layout.actuator_count)
        seen = sorted(set(comm.allgather(mine)))
        if len(seen) > 1:
            raise ValueError(f"ShardedBatch: worlds differ between ranks: {seen} "
                             "(bodies, coordinates, dofs, articulations, actuators per world)")

    @property
    def range(self):
        """The global worlds this rank owns (a novaphy.WorldRange)."""
        return _novaphy.shard_range(self.world_count, self.rank, self.size)

    def step(self, dt):
        """Collide and step this rank's worlds by dt; collective. If any rank fails, every rank raises
        ValueError and no rank changes its state."""

        def advance():
            self.pipeline.collide(self.state, self.contacts)
            self.solver.step(self.state, self._next, self.control, self.contacts, dt)

        _collectively(self.comm, advance)
        self.state.assign(self._next)

    def diverged(self):
        """Per local world: 1 where the last step's divergence guard fired on one of its articulations."""
        flags = np.asarray(self.solver.diverged, dtype=np.uint8)
        return flags.reshape(self.range.count, -1).max(axis=1) if flags.size else np.zeros(self.range.count, np.uint8)

    def _width(self, local, what):
        """Values per world of `local` (this rank's worlds), the same on every rank, with its dtype."""
        count = self.range.count
        error = None
        if count > 0 and local.size % count != 0:
            error = f"{what}: {local.size} local values do not split into {count} worlds"
        elif count == 0 and local.size > 0:
            error = f"{what}: {local.size} local values on a rank without worlds"
        _agree(self.comm, error)
        mine = (local.size // count if count > 0 else None, local.dtype.str, local.shape[1:])
        seen = {m for m in self.comm.allgather(mine) if m[0] is not None}
        if len(seen) > 1:
            raise ValueError(f"{what}: ranks disagree on (values per world, dtype, row shape): {sorted(seen)}")
        return seen.pop() if seen else (0, local.dtype.str, local.shape[1:])

    def _layout(self, width, dtype):
        counts = [r.count * width for r in self._ranges]
        displs = [r.begin * width for r in self._ranges]
        return counts, displs, MPI._typedict[np.dtype(dtype).char]

    def _check_root(self, root, what):
        if not 0 <= root < self.size:
            raise ValueError(f"{what}: root must be in [0, {self.size}), got {root}")

    def gather(self, local, root=0):
        """All worlds' values of `local` (this rank's worlds, world-major, e.g. batch.state.joint_q) on
        `root` as one array of world_count times the rows; None on the other ranks."""
        self._check_root(root, "gather")
        local = np.ascontiguousarray(local)
        width, dtype, row = self._width(local, "gather")
        counts, displs, mpi_type = self._layout(width, dtype)
        out = np.empty(self.world_count * width, dtype=dtype) if self.rank == root else None
        self.comm.Gatherv(local.reshape(-1), [out, counts, displs, mpi_type], root=root)
        return out.reshape((-1,) + row) if out is not None else None

    def all_gather(self, local):
        """As gather, with the result on every rank."""
        local = np.ascontiguousarray(local)
        width, dtype, row = self._width(local, "all_gather")
        counts, displs, mpi_type = self._layout(width, dtype)
        out = np.empty(self.world_count * width, dtype=dtype)
        self.comm.Allgatherv(local.reshape(-1), [out, counts, displs, mpi_type])
        return out.reshape((-1,) + row)

    def scatter(self, global_values, local, root=0):
        """Writes each rank's worlds of `global_values` (read on `root` only; all worlds, world-major)
        into `local` in place, e.g. batch.control.joint_f, so the engine sees them at the next step."""
        self._check_root(root, "scatter")
        if not (isinstance(local, np.ndarray) and local.flags.c_contiguous and local.flags.writeable):
            raise ValueError("scatter: local must be a writable C-contiguous numpy array (a view of the engine)")
        width, dtype, _ = self._width(local, "scatter")
        counts, displs, mpi_type = self._layout(width, dtype)
        error = None
        if self.rank == root:
            global_values = np.ascontiguousarray(global_values, dtype=dtype)
            if global_values.size != self.world_count * width:
                error = (f"scatter: the global array holds {global_values.size} values, "
                         f"{self.world_count} worlds need {self.world_count * width}")
        _agree(self.comm, error)
        send = [global_values.reshape(-1), counts, displs, mpi_type] if self.rank == root else None
        self.comm.Scatterv(send, local.reshape(-1), root=root)
