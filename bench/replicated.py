"""A robot file replicated into worlds, ready to step: what the benchmarks that time a build in a process of their
own (ab_builds.py, randomise.py) set up there. Only novaphy's Python API: any build imports it."""
import warnings

import novaphy


def replicated(scene, precision, threads, worlds):
    """The model of `worlds` copies of the robot in `scene` in precision `precision` (a novaphy.Precision name), its
    state and control at its first keyframe where it has one, and a solver and pipeline on `threads` threads:
    (model, state, control, solver, pipeline, contacts)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = novaphy.ModelBuilder()
        robot.add_mjcf(scene)
        builder = novaphy.ModelBuilder()
        builder.precision = getattr(novaphy.Precision, precision)
        builder.replicate(robot, worlds)
        model = builder.finalize()
    key = model.keyframes[0] if model.keyframes else None
    state = model.state(keyframe=key) if key else model.state()
    control = model.control(keyframe=key) if key else model.control()
    solver = novaphy.solvers.SolverFeatherstone(model)
    solver.settings.num_threads = threads
    pipeline = novaphy.CollisionPipeline(model, num_threads=threads)
    return model, state, control, solver, pipeline, pipeline.contacts()
