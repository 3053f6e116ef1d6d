"""novaphy.mpi.ShardedBatch under `mpirun -np 2 python3 -m pytest` (ctest runs it so): the same checks as
the C++ ShardedBatch tests, through mpi4py."""

import os

import numpy as np
import pytest
from mpi4py import MPI

import novaphy
from novaphy.mpi import ShardedBatch

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "scenes", "quadruped.xml")
COMM = MPI.COMM_WORLD


def quadruped(builder, w):
    builder.add_mjcf(SCENE, xform=novaphy.Transform([1.5 * (w % 3), 1.5 * (w // 3), 0.3]), static_shapes=False)


def ground():
    shared = novaphy.ModelBuilder(gravity=[0.0, 0.0, -9.81])
    shared.add_plane([0.0, 0.0, 1.0], 0.0)
    return shared


def test_two_ranks():
    assert COMM.Get_size() == 2, "run under mpirun -np 2"


def test_sharded_worlds_step_bit_identically_to_one_process():
    worlds, dt = 5, 0.005
    batch = ShardedBatch(COMM, worlds, quadruped, ground())
    assert batch.range.count == (3 if batch.rank == 0 else 2)
    model = novaphy.build_worlds(ground(), quadruped, novaphy.shard_range(worlds, 0, 1))
    pipeline = novaphy.CollisionPipeline(model)
    contacts = pipeline.contacts()
    solver = novaphy.solvers.SolverFeatherstone(model)
    state, control = model.state(), model.control()
    nv = batch.layout.joint_dof_count
    for s in range(120):
        f = 3 * np.sin(0.01 * s + 0.7 * np.arange(worlds * nv))
        batch.scatter(f if batch.rank == 0 else None, batch.control.joint_f)
        control.joint_f[:] = f
        batch.step(dt)
        pipeline.collide(state, contacts)
        solver.step(state, state, control, contacts, dt)
    q = batch.all_gather(batch.state.joint_q)
    body_q = batch.all_gather(batch.state.body_q)
    assert np.array_equal(q, state.joint_q)
    assert np.array_equal(body_q, state.body_q)
    assert body_q.shape == (model.body_count, 7)
    assert abs(q[2] - 0.75) > 0.1  # the robots moved


def test_gather_and_scatter_place_values_in_world_order():
    batch = ShardedBatch(COMM, 7, quadruped, ground())
    r = batch.range
    local = np.stack([np.arange(r.begin, r.end) * 10, -np.arange(r.begin, r.end)], axis=1)
    out = batch.gather(local, root=1)
    if batch.rank == 1:
        assert np.array_equal(out, np.stack([np.arange(7) * 10, -np.arange(7)], axis=1))
    else:
        assert out is None
    mine = np.zeros(3 * r.count)
    batch.scatter(0.5 * np.arange(21) if batch.rank == 0 else None, mine)
    assert np.array_equal(mine, 0.5 * np.arange(3 * r.begin, 3 * r.end))
    with pytest.raises(ValueError, match="rank 0: scatter: the global array holds 20 values, 7 worlds need 21"):
        batch.scatter(np.zeros(20), mine)
    ragged = np.zeros(2 * r.count if batch.rank == 0 else 3 * r.count)
    with pytest.raises(ValueError, match="all_gather: ranks disagree"):
        batch.all_gather(ragged)
    with pytest.raises(ValueError, match="gather: root must be in"):
        batch.gather(local, root=2)
    with pytest.raises(ValueError, match="writable C-contiguous"):
        batch.scatter(None, batch.solver.diverged)


def test_an_error_on_one_rank_is_raised_on_every_rank_and_no_state_changes():
    batch = ShardedBatch(COMM, 4, quadruped, ground())
    before = batch.state.joint_q.copy()
    if batch.rank == 1:
        batch.control.joint_f[20] = np.nan
    with pytest.raises(ValueError, match=r"rank 1: joint_f\[20\] is not finite"):
        batch.step(0.005)
    assert np.array_equal(batch.state.joint_q, before)
    with pytest.raises(ValueError, match=r"rank 0: ShardedBatch: world_count must be at least the number of ranks \(2\), got 1"):
        ShardedBatch(COMM, 1, quadruped, ground())

    def uneven(builder, w):
        for _ in range(w // 2 + 1):
            builder.add_body(novaphy.RigidBody.from_sphere(1.0, 0.1))

    with pytest.raises(ValueError, match="worlds differ between ranks"):
        ShardedBatch(COMM, 4, uneven, ground())


def test_diverged_worlds_are_flagged_and_gathered():
    batch = ShardedBatch(COMM, 6, quadruped, ground())
    if batch.rank == 1:
        batch.state.joint_qd[batch.layout.joint_dof_count + 8] = 1e7  # world 4
    batch.step(0.005)
    flags = batch.gather(batch.diverged())
    if batch.rank == 0:
        assert flags.tolist() == [0, 0, 0, 0, 1, 0]
