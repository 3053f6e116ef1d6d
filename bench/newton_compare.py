"""NovaPhy beside NVIDIA Newton (PyPI `newton`, warp's CPU backend) on the same scenes, one thread, in one run.

Runs in the virtual environment tools/setup_newton.sh makes (build/venv-newton: newton and warp-lang from PyPI)
and imports NovaPhy from build/python (built for the same Python as /usr/bin/python3):

    bash tools/setup_newton.sh
    OMP_NUM_THREADS=1 build/venv-newton/bin/python bench/newton_compare.py [--steps 500] [--worlds 1 64]
        [--out bench/results/newton_compare.md]

Scenes, each built with each engine's own builder: a 15-link pendulum chain of revolute joints (boxes, collisions
off), a 20-segment rope of ball joints (boxes, collisions off), and Go1 (Menagerie scene.xml: robot and floor) at
the file's timestep from its `home` keyframe (position targets at the keyframe's ctrl). Solvers: Featherstone,
SemiImplicit and XPBD of each engine, defaults; Newton's XPBD is stepped as 8 substeps of dt/8 (collide once per
step), NovaPhy's substeps internally (settings.substeps = 8, its default). Per configuration: one untimed full-length
run (kernel compilation, warm-up; its final state gives the accuracy figure), then 3 timed runs from the initial state;
the median is reported as robot-steps per wall second. Accuracy: the distance of one body's final position (chain:
tip link, rope: last segment, Go1: trunk; world 0) from NovaPhy SolverFeatherstone at dt/10 (its own distance from
dt/20 is reported as the reference's error bar).
"""

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(ROOT, "build", "python"))

import numpy as np  # noqa: E402
import warp as wp  # noqa: E402

wp.config.quiet = True
import newton  # noqa: E402

import novaphy  # noqa: E402

GO1 = "/work/shared/robots/unitree_go1/scene.xml"
SOLVERS = ["Featherstone", "SemiImplicit", "XPBD"]
XPBD_SUBSTEPS = 8
G = 9.81

# The two chains: (links, joint type, half extents of a box link along x, mass of a link, dt, pivot height)
CHAIN = dict(n=15, joint="revolute", half=(0.25, 0.05, 0.05), mass=1.0, dt=0.002, z=10.0)
ROPE = dict(n=20, joint="ball", half=(0.05, 0.01, 0.01), mass=0.1, dt=0.002, z=10.0)


def box_inertia(mass, half):
    hx, hy, hz = half
    return np.diag([mass * (hy * hy + hz * hz) / 3, mass * (hx * hx + hz * hz) / 3, mass * (hx * hx + hy * hy) / 3])


# ---------------------------------------------------------------------------------------------------- NovaPhy side
def novaphy_chain(spec):
    b = novaphy.ModelBuilder(gravity=np.array([0.0, 0.0, -G]))
    hx = spec["half"][0]
    joints, parent = [], -1
    for i in range(spec["n"]):
        body = novaphy.RigidBody(spec["mass"], np.zeros(3), box_inertia(spec["mass"], spec["half"]))
        link = b.add_body(body, xform=novaphy.Transform(np.array([hx * (2 * i + 1), 0.0, spec["z"]])))
        b.add_shape_box(link, np.array(spec["half"]), collision_group=0, collision_mask=0)
        pxf = novaphy.Transform(np.array([0.0, 0.0, spec["z"]]) if parent < 0 else np.array([hx, 0.0, 0.0]))
        cxf = novaphy.Transform(np.array([-hx, 0.0, 0.0]))
        if spec["joint"] == "revolute":
            j = b.add_joint_revolute(parent, link, parent_xform=pxf, child_xform=cxf, axis=np.array([0.0, 1.0, 0.0]))
        else:
            j = b.add_joint_ball(parent, link, parent_xform=pxf, child_xform=cxf)
        joints.append(j)
        parent = link
    b.add_articulation(joints)
    return b


def novaphy_go1():
    b = novaphy.ModelBuilder()
    b.add_mjcf(GO1)
    return b


class Run:
    """What both engines' runs share: the first step at which a run from the start goes non-finite."""

    def first_nonfinite(self, steps):
        self.reset()
        for i in range(steps):
            self.run(1)
            if not self.finite():
                return i + 1
        return None


class NovaPhyRun(Run):
    def __init__(self, scene, solver, worlds, dt_scale=1):
        one = novaphy_go1() if scene == "go1" else novaphy_chain(CHAIN if scene == "chain" else ROPE)
        if worlds > 1:
            b = novaphy.ModelBuilder()
            b.replicate(one, worlds)
        else:
            b = one
        self.model = b.finalize()
        m = self.model
        key = m.keyframes[0] if m.keyframes else None
        self.init = m.state(keyframe=key) if key else m.state()
        self.state = self.init.copy()
        self.control = m.control(keyframe=key) if key else m.control()
        cls = getattr(novaphy.solvers, "Solver" + solver)
        self.solver = cls(m)
        self.solver.settings.num_threads = 1
        self.pipeline = novaphy.CollisionPipeline(m, num_threads=1)
        self.contacts = self.pipeline.contacts()
        self.dt = (m.timestep if scene == "go1" else (CHAIN if scene == "chain" else ROPE)["dt"]) / dt_scale
        names = list(m.body_name)
        self.track = names.index("trunk") if scene == "go1" else (CHAIN if scene == "chain" else ROPE)["n"] - 1
        self.bodies_per_world = m.body_count // worlds

    def reset(self):
        self.state.assign(self.init)

    def run(self, steps):
        p, c, s, st, ctl, dt = self.pipeline, self.contacts, self.solver, self.state, self.control, self.dt
        t = time.perf_counter()
        for _ in range(steps):
            p.collide(st, c)
            s.step(st, st, ctl, c, dt)
        return time.perf_counter() - t

    def body_q(self):
        return np.array(self.state.body_q)

    def finite(self):
        return bool(np.isfinite(self.state.body_q).all() and np.isfinite(self.state.body_qd).all())


# ----------------------------------------------------------------------------------------------------- Newton side
def newton_chain(spec):
    b = newton.ModelBuilder()  # Z up, gravity -9.81 z
    hx = spec["half"][0]
    cfg = newton.ModelBuilder.ShapeConfig(density=0.0, has_shape_collision=False, has_particle_collision=False)
    inertia = wp.mat33(*box_inertia(spec["mass"], spec["half"]).flatten())
    joints, parent = [], -1
    for i in range(spec["n"]):
        link = b.add_link(xform=wp.transform(wp.vec3(hx * (2 * i + 1), 0.0, spec["z"]), wp.quat_identity()),
                          mass=spec["mass"], inertia=inertia, lock_inertia=True)
        b.add_shape_box(link, hx=spec["half"][0], hy=spec["half"][1], hz=spec["half"][2], cfg=cfg)
        pxf = wp.transform(wp.vec3(0.0, 0.0, spec["z"]) if parent < 0 else wp.vec3(hx, 0.0, 0.0), wp.quat_identity())
        cxf = wp.transform(wp.vec3(-hx, 0.0, 0.0), wp.quat_identity())
        if spec["joint"] == "revolute":
            j = b.add_joint_revolute(parent, link, parent_xform=pxf, child_xform=cxf, axis=wp.vec3(0.0, 1.0, 0.0))
        else:
            j = b.add_joint_ball(parent, link, parent_xform=pxf, child_xform=cxf)
        joints.append(j)
        parent = link
    b.add_articulation(joints)
    return b, None


def newton_go1():
    b = newton.ModelBuilder()
    # The mesh geoms are visual-only (and need trimesh to load); the colliders are primitives.
    b.add_mjcf(GO1, parse_visuals=False)
    # Newton's MJCF importer does not apply the keyframe: take `home` (MuJoCo quaternion w,x,y,z -> x,y,z,w).
    qpos = np.array([0, 0, 0.27, 1, 0, 0, 0] + [0, 0.9, -1.8] * 4, dtype=float)
    ctrl = np.array([0, 0.9, -1.8] * 4, dtype=float)
    q = np.concatenate([qpos[:3], qpos[4:7], qpos[3:4], qpos[7:]])
    return b, (q, ctrl)


class NewtonRun(Run):
    def __init__(self, scene, solver, worlds):
        wp.set_device("cpu")
        one, key = newton_go1() if scene == "go1" else newton_chain(CHAIN if scene == "chain" else ROPE)
        if worlds > 1:
            b = newton.ModelBuilder()
            b.replicate(one, worlds)
        else:
            b = one
        self.model = m = b.finalize(device="cpu")
        if key is not None:
            q, ctrl = key
            m.joint_q.assign(np.tile(q, worlds).astype(np.float32))
            ntarget = m.joint_target_q.shape[0] // worlds
            tq = m.joint_target_q.numpy()[:ntarget].astype(float)
            tq[-len(ctrl):] = ctrl  # the 12 actuated hinges follow the free joint's 6 (or 7) entries
            m.joint_target_q.assign(np.tile(tq, worlds).astype(np.float32))
        self.q0 = m.joint_q.numpy().copy()
        self.qd0 = m.joint_qd.numpy().copy()
        self.s0, self.s1 = m.state(), m.state()
        self.control = m.control()
        if key is not None and self.control.joint_target_q is not None:
            wp.copy(self.control.joint_target_q, m.joint_target_q)
        self.solver_name = solver
        self.solver = getattr(newton.solvers, "Solver" + solver)(m)
        self.pipeline = newton.CollisionPipeline(m)
        self.contacts = self.pipeline.contacts()
        self.dt = 0.002 if scene == "go1" else (CHAIN if scene == "chain" else ROPE)["dt"]
        labels = list(m.body_label)
        self.track = ([i for i, lbl in enumerate(labels) if lbl.split("/")[-1] == "trunk"][0] if scene == "go1"
                      else (CHAIN if scene == "chain" else ROPE)["n"] - 1)
        self.reset()

    def reset(self):
        m = self.model
        for s in (self.s0, self.s1):
            s.joint_q.assign(self.q0)
            s.joint_qd.assign(self.qd0)
            newton.eval_fk(m, s.joint_q, s.joint_qd, s)
            s.clear_forces()

    def run(self, steps):
        sub = XPBD_SUBSTEPS if self.solver_name == "XPBD" else 1
        h = self.dt / sub
        solver, pipeline, contacts, control = self.solver, self.pipeline, self.contacts, self.control
        s0, s1 = self.s0, self.s1
        t = time.perf_counter()
        for _ in range(steps):
            pipeline.collide(s0, contacts)
            for _ in range(sub):
                s0.clear_forces()
                solver.step(s0, s1, control, contacts, h)
                s0, s1 = s1, s0
        wp.synchronize()
        elapsed = time.perf_counter() - t
        self.s0, self.s1 = s0, s1
        return elapsed

    def body_q(self):
        return self.s0.body_q.numpy()

    def finite(self):
        return bool(np.isfinite(self.s0.body_q.numpy()).all() and np.isfinite(self.s0.body_qd.numpy()).all())


# ------------------------------------------------------------------------------------------------------ measuring
def reference(scene, steps):
    """World-0 tracked body position from NovaPhy SolverFeatherstone at dt/10, and its distance from dt/20."""
    out = []
    for scale in (10, 20):
        r = NovaPhyRun(scene, "Featherstone", 1, dt_scale=scale)
        r.run(steps * scale)
        out.append(r.body_q()[r.track, :3].copy())
    return out[0], float(np.linalg.norm(out[0] - out[1]))


def measure(engine, scene, solver, worlds, steps, rounds, ref):
    row = dict(engine=engine, scene=scene, solver=solver, worlds=worlds)
    try:
        t = time.perf_counter()
        r = (NovaPhyRun if engine == "NovaPhy" else NewtonRun)(scene, solver, worlds)
        r.run(steps)  # warm-up, also compiles warp's kernels on first use
        row["setup_s"] = time.perf_counter() - t
        q = r.body_q()
        row["finite_warmup"] = r.finite()
        row["pos"] = q[r.track, :3].copy()
        row["error"] = float(np.linalg.norm(row["pos"] - ref)) if row["finite_warmup"] else float("nan")
        times, finite = [], []
        for _ in range(rounds):
            r.reset()
            times.append(r.run(steps))
            finite.append(r.finite())
        row["times"] = times
        row["rate"] = steps * worlds / statistics.median(times)
        row["finite"] = all(finite) and row["finite_warmup"]
        row["nan_step"] = None if row["finite"] else r.first_nonfinite(steps)
        if worlds > 1 and row["finite"]:
            # every world starts alike: their tracked bodies should agree
            bq = r.body_q()
            per = bq.shape[0] // worlds
            row["world_spread"] = float(np.abs(bq[r.track::per, :3][:worlds] - bq[r.track, :3]).max())
    except Exception as e:  # report what fails rather than stopping
        row["error_msg"] = f"{type(e).__name__}: {e}".splitlines()[0][:300]
    print(fmt_progress(row), flush=True)
    return row


def fmt_progress(row):
    if "error_msg" in row:
        return f"{row['scene']:6} {row['solver']:13} {row['engine']:8} w={row['worlds']:3}  FAILED {row['error_msg']}"
    return (f"{row['scene']:6} {row['solver']:13} {row['engine']:8} w={row['worlds']:3}  {row['rate']:12.0f} robot-steps/s"
            f"  finite={row['finite']} nan_step={row['nan_step']} err={row['error']:.3g} pos={np.round(row['pos'], 4)}"
            f" setup={row['setup_s']:.1f}s")


def fmt_rate(row):
    return "failed" if "error_msg" in row else f"{row['rate']:,.0f}"


def fmt_finite(row, steps):
    if "error_msg" in row:
        return "—"
    if row["finite"]:
        return "yes"
    return f"**no** (NaN/inf from step {row['nan_step']} of {steps})" if row["nan_step"] else "**no**"


def fmt_err(row):
    if "error_msg" in row or not np.isfinite(row.get("error", np.nan)):
        return "—"
    return f"{row['error']:.3g} m"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--worlds", type=int, nargs="+", default=[1, 64])
    parser.add_argument("--scenes", nargs="+", default=["chain", "rope", "go1"])
    parser.add_argument("--out")
    args = parser.parse_args()
    wp.init()
    wp.set_device("cpu")

    load_start = os.getloadavg()
    # the commit and tree as the module was loaded (a build may land, and HEAD move, while this runs)
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no", "--", ".",
                            ":!bench/newton_compare.py", ":!bench/results"], capture_output=True, text=True).stdout.strip()
    so_mtime = os.path.getmtime(novaphy._novaphy.__file__)
    so_time = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(so_mtime))
    t_start = time.time()
    rows, refs = [], {}
    for scene in args.scenes:
        refs[scene] = reference(scene, args.steps)
        print(f"{scene}: reference {refs[scene][0]} (dt/10 vs dt/20: {refs[scene][1]:.2g} m)", flush=True)
        for worlds in args.worlds:
            for solver in SOLVERS:
                for engine in ("NovaPhy", "Newton"):
                    rows.append(measure(engine, scene, solver, worlds, args.steps, args.rounds, refs[scene][0]))

    load_end = os.getloadavg()
    so_changed = os.path.getmtime(novaphy._novaphy.__file__) != so_mtime
    cpu = next((ln.split(":", 1)[1].strip() for ln in subprocess.run(["lscpu"], capture_output=True, text=True)
                .stdout.splitlines() if ln.startswith("Model name")), platform.processor())
    commit_end = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip()
    cmd = "OMP_NUM_THREADS=1 build/venv-newton/bin/python bench/newton_compare.py " + " ".join(
        [f"--steps {args.steps}", f"--rounds {args.rounds}", "--worlds " + " ".join(map(str, args.worlds)),
         "--scenes " + " ".join(args.scenes)] + ([f"--out {args.out}"] if args.out else []))
    dts = {"chain": CHAIN["dt"], "rope": ROPE["dt"], "go1": 0.002}
    lines = ["# NovaPhy beside NVIDIA Newton on CPU, one thread", "",
             f"Made by `{cmd}` (from /work/main).", "",
             f"- Machine: {cpu}, {os.cpu_count()} logical CPUs, everything on 1 thread (OMP_NUM_THREADS=1, NovaPhy "
             "`settings.num_threads = 1` and `CollisionPipeline(num_threads=1)`, warp's CPU backend runs kernels "
             f"serially). Load average (1/5/15 min) at the start {load_start[0]:.2f}/{load_start[1]:.2f}/{load_start[2]:.2f}"
             f", at the end {load_end[0]:.2f}/{load_end[1]:.2f}/{load_end[2]:.2f} (other work shared the 2 CPUs); the "
             f"whole run took {(time.time() - t_start) / 60:.1f} min.",
             f"- Versions: newton {newton.__version__}, warp-lang {wp.__version__}, NovaPhy {commit} at the start"
             + (" (with uncommitted changes in tracked files)" if dirty else "")
             + f" (its module {os.path.basename(novaphy._novaphy.__file__)} modified {so_time}"
             + (", **rebuilt during the run**" if so_changed else "")
             + (f"; HEAD moved to {commit_end} during the run" if commit_end != commit else "")
             + f"), Python {platform.python_version()}, "
             f"NumPy {np.__version__}.",
             f"- Each row: one untimed run of {args.steps} steps (Newton compiles its kernels here; its final state gives the "
             f"error), then {args.rounds} timed runs of {args.steps} steps from the initial state; robot-steps/s = steps × "
             f"worlds / median wall time of the timed runs (collision + solver step, the engine's whole Python loop).",
             "- finite?: every body pose and velocity finite at the end of every run; where not, the first step with a non-finite pose or velocity.",
             "- error: distance of the tracked body's final position (world 0) from NovaPhy SolverFeatherstone at dt/10 "
             "over the same simulated time.", ""]
    for scene in args.scenes:
        title = {"chain": f"15-link pendulum chain (revolute joints, boxes, no contacts), released horizontal, "
                          f"dt = {dts['chain']} s, tracked body: tip link",
                 "rope": f"20-segment rope (ball joints, boxes, no contacts), released horizontal, dt = {dts['rope']} s, "
                         f"tracked body: last segment",
                 "go1": "Go1 (Menagerie scene.xml: robot + floor plane), `home` keyframe and its position targets, "
                        "dt = 0.002 s (the file's, MuJoCo's default), tracked body: trunk"}[scene]
        ref, ref_err = refs[scene]
        lines += [f"## {title}", "",
                  f"Simulated time {args.steps * dts[scene]:.2f} s. Reference position {np.round(ref, 4).tolist()} m "
                  f"(its distance from dt/20: {ref_err:.2g} m).", ""]
        for worlds in args.worlds:
            lines += [f"### {worlds} world{'s' if worlds > 1 else ''}", "",
                      "| solver | engine | robot-steps/s | finite? | error | NovaPhy / Newton |", "|---|---|---:|---|---:|---:|"]
            for solver in SOLVERS:
                pair = {r["engine"]: r for r in rows if r["scene"] == scene and r["worlds"] == worlds and r["solver"] == solver}
                for engine in ("NovaPhy", "Newton"):
                    r = pair[engine]
                    ratio = ""
                    if engine == "NovaPhy" and "rate" in pair["NovaPhy"] and "rate" in pair["Newton"]:
                        ratio = f"{pair['NovaPhy']['rate'] / pair['Newton']['rate']:.1f}×"
                    note = f" (failed: `{r['error_msg']}`)" if "error_msg" in r else ""
                    lines.append(f"| {solver} | {engine}{note} | {fmt_rate(r)} | {fmt_finite(r, args.steps)} | "
                                 f"{fmt_err(r)} | {ratio} |")
            lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
