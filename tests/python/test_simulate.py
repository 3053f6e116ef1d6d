"""novaphy.simulate: substeps of collide and step in one call, the same bits as the loop written out."""
import numpy as np
import pytest

import novaphy


def scene_of(model):
    pipeline = novaphy.CollisionPipeline(model)
    return pipeline, novaphy.solvers.SolverFeatherstone(model), model.state(), model.control(), pipeline.contacts()


def test_substeps_equal_the_loop_and_default_to_the_models_timestep(scene):
    robot = novaphy.ModelBuilder()
    robot.add_mjcf(scene("quadruped.xml"))
    builder = novaphy.ModelBuilder()
    builder.replicate(robot, 2)
    model = builder.finalize()
    assert model.timestep == 0.005
    looped, simulated = scene_of(model), scene_of(model)
    for action in range(20):
        for _, _, _, control, _ in (looped, simulated):
            control.joint_f[:] = 0.1 * action
        pipeline, solver, state, control, contacts = looped
        for _ in range(4):
            pipeline.collide(state, contacts)
            solver.step(state, state, control, contacts, model.timestep)
        novaphy.simulate(*simulated, substeps=4)
    np.testing.assert_array_equal(simulated[2].joint_q, looped[2].joint_q)
    np.testing.assert_array_equal(simulated[2].body_qd, looped[2].body_qd)
    with pytest.raises(ValueError, match="simulate: substeps must be >= 1, got 0"):
        novaphy.simulate(*simulated, substeps=0)
    with pytest.raises(ValueError, match="simulate: dt must be finite and >= 0"):
        novaphy.simulate(*simulated, dt=-1.0)
