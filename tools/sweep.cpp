// The speed/accuracy sweep: steps one scene under many solver settings and measures, for each,
// throughput (robot-steps/s) against error from a reference run (float64, dt/16 of the smallest dt,
// 200 PGS iterations; and, for a scene without contacts, MuJoCo's RK4 at the same dt on the same
// MJCF): trajectory error at the sample times, energy error, penetration and limit overshoot.
//   novaphy_sweep [--scene chain15|quadruped|grid|FILE.xml] [--no-contacts] [--side N]
//                 [--seconds 1,10] [--threads N] [--out PREFIX] [--no-progress]
// Scenes: chain15 (no contacts), quadruped (one sprung quadruped dropped 0.3 m onto the ground), grid
// (side x side of them, default 10 x 10), or any MJCF/URDF (its own floor; --no-contacts drops it).
// Writes PREFIX.csv (default sweep_<scene>.csv): per setting robot-steps/s and robot-seconds/s
// (simulated seconds per wall second, what a larger dt buys); tools/sweep_report.py turns it into a
// markdown table and a Pareto plot. Angular damping is off in every run: the errors are those of the integrator and
// the constraint solver, not of a damping model.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/error.h"
#include "engine/solver/solver_featherstone.h"
#include "tools/progress.h"
#include "tools/robot_grid.h"

namespace novaphy {
namespace {

struct Options {
  std::string scene = "quadruped";
  bool contacts = true;
  int side = 10;                       // the grid: side x side robots
  std::vector<double> seconds{1, 10};  // sample times, the last one the run's length
  int threads = 1;
  std::string out;
  bool progress = true;
};

struct Scene {
  std::string name, path;
  bool contacts = true;
  int side = 0;  // > 0: side x side copies dropped 0.3 m onto a shared ground (the quadruped: 1)
};

// one row of the sweep: the settings it changes from the defaults
struct Setting {
  std::string label;
  double dt = 1.0 / 240;
  int iterations = 20;
  int interval = 1;
  bool tile = false, fuse = true, warm = true;
  double coriolis = 0;  // coriolis_implicitness
  double pgs_tolerance = SolverFeatherstoneSettings{}.pgs_tolerance;
};

struct Result {
  double robot_steps_per_s = 0;
  std::vector<std::vector<Scalar>> q;  // joint_q at each sample time
  Scalar energy = 0;                   // at the last sample time
  Scalar penetration = 0, overshoot = 0;
  long diverged_steps = 0;
};

Scene scene_of(const Options& o) {
  if (o.scene == "chain15") return {"chain15", NOVAPHY_SCENE_DIR "/chain15.xml", false, 0};
  if (o.scene == "quadruped") return {"quadruped", NOVAPHY_SCENE_DIR "/quadruped.xml", true, 1};
  if (o.scene == "grid") return {"grid", NOVAPHY_SCENE_DIR "/quadruped.xml", true, o.side};
  const size_t slash = o.scene.find_last_of('/'), dot = o.scene.find_last_of('.');
  return {o.scene.substr(slash + 1, dot == std::string::npos ? std::string::npos : dot - slash - 1), o.scene,
          o.contacts, 0};
}

// a scene's model and its first state; for a single file also MuJoCo's model of it and the map
// from MuJoCo's coordinates to NovaPhy's (the file is parsed once)
struct Loaded {
  Model model;
  State start;
  std::unique_ptr<mjModel, void (*)(mjModel*)> mujoco{nullptr, mj_deleteModel};
  MujocoImport import;
};

Loaded load(const Scene& scene) {
  Loaded loaded;
  if (scene.side > 0) {
    // the 100-robot grid (or one robot of it): each robot its own world, 0.3 m above one shared ground
    loaded.model = build_worlds(grid_ground(), robot_grid(scene.path, scene.side, 0.3), {0, scene.side * scene.side});
    loaded.start = loaded.model.state();
    return loaded;
  }
  // a single file starts from MuJoCo's qpos0
  loaded.mujoco.reset(load_mujoco_model(scene.path));
  ModelBuilder builder;
  ImportOptions options;
  options.static_shapes = scene.contacts;
  loaded.import = import_mujoco_model(builder, loaded.mujoco.get(), options);
  loaded.model = builder.finalize();
  loaded.start = loaded.model.state();
  loaded.import.to_joint_q(loaded.mujoco->qpos0, loaded.start.joint_q.data());
  eval_fk(loaded.model, loaded.start);
  return loaded;
}

int steps_to(double seconds, double dt) { return static_cast<int>(std::lround(seconds / dt)); }

Result run(const Model& model, const Scene& scene, const State& start, const Setting& setting, const Options& o,
           ProgressBar& bar, int& done) {
  const std::vector<double>& seconds = o.seconds;
  CollisionOptions collision;
  collision.self_collision = scene.contacts;
  CollisionPipeline pipeline(model, collision);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_iterations = setting.iterations;
  settings.update_mass_matrix_interval = setting.interval;
  settings.use_tile_gemm = setting.tile;
  settings.fuse_cholesky = setting.fuse;
  settings.use_warmstarting = setting.warm;
  settings.coriolis_implicitness = setting.coriolis;
  settings.pgs_tolerance = setting.pgs_tolerance;
  settings.angular_damping = 0;
  settings.on_divergence = DivergencePolicy::Flag;
  settings.num_threads = o.threads;
  SolverFeatherstone solver(model, settings);
  State state = start;
  const Control control = model.control();

  // limited 1-dof joints: coordinate and range
  struct Limit {
    int coord;
    Scalar lower, upper;
  };
  std::vector<Limit> limits;
  for (int j = 0; j < model.joint_count; ++j) {
    const int dof = model.joint_qd_start[j];
    if (model.joint_qd_start[j + 1] - dof != 1) continue;
    if (std::isfinite(model.joint_limit_lower[dof]) || std::isfinite(model.joint_limit_upper[dof]))
      limits.push_back({model.joint_q_start[j], model.joint_limit_lower[dof], model.joint_limit_upper[dof]});
  }

  Result result;
  double busy = 0;
  int sample = 0;
  const int steps = steps_to(seconds.back(), setting.dt);
  for (int s = 1; s <= steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    if (scene.contacts) pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, setting.dt);
    busy += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (int c = 0; c < contacts.contact_count; ++c)
      result.penetration = std::max(result.penetration, contacts.contact_depth[c]);
    for (const Limit& l : limits) {
      const Scalar q = state.joint_q[l.coord];
      result.overshoot = std::max({result.overshoot, q - l.upper, l.lower - q});
    }
    for (const std::uint8_t flag : solver.diverged())
      if (flag) {
        ++result.diverged_steps;
        break;
      }
    if (s == steps_to(seconds[sample], setting.dt)) {
      result.q.push_back(state.joint_q);
      ++sample;
    }
    bar.update(++done);
  }
  result.energy = eval_energy(model, state);
  int robots = 0;
  for (int a = 0; a < model.articulation_count; ++a) robots += model.articulation(a).dof_count() > 0;
  result.robot_steps_per_s = busy > 0 ? robots * steps / busy : 0;
  return result;
}

// MuJoCo's RK4 on the same MJCF at dt, contacts off: joint_q (NovaPhy's coordinates) at each sample time
std::vector<std::vector<Scalar>> mujoco_rk4(const Loaded& loaded, double dt, const std::vector<double>& seconds) {
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(mj_copyModel(nullptr, loaded.mujoco.get()), mj_deleteModel);
  m->opt.integrator = mjINT_RK4;
  m->opt.timestep = dt;
  m->opt.disableflags |= mjDSBL_CONTACT;
  const std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m.get()), mj_deleteData);
  std::vector<std::vector<Scalar>> q;
  int done = 0;
  for (const double t : seconds) {
    for (; done < steps_to(t, dt); ++done) mj_step(m.get(), d.get());
    q.emplace_back(loaded.model.joint_coord_count);
    loaded.import.to_joint_q(d->qpos, q.back().data());
  }
  return q;
}

Scalar max_difference(const std::vector<Scalar>& a, const std::vector<Scalar>& b) {
  Scalar d = 0;
  for (size_t k = 0; k < a.size(); ++k) d = std::max(d, std::abs(a[k] - b[k]));
  return d;
}

std::vector<Setting> settings_to_sweep() {
  std::vector<Setting> sweep;
  for (const int dt_inv : {60, 120, 240, 480})
    for (const int iterations : {5, 10, 20, 50}) {
      Setting s;
      s.dt = 1.0 / dt_inv;
      s.iterations = iterations;
      s.label = "dt 1/" + std::to_string(dt_inv) + " it " + std::to_string(iterations);
      sweep.push_back(s);
    }
  // implicit Coriolis forces (linearised midpoint) at each dt
  for (const int dt_inv : {60, 120, 240, 480}) {
    Setting s;
    s.dt = 1.0 / dt_inv;
    s.coriolis = 0.5;
    s.label = "dt 1/" + std::to_string(dt_inv) + " midpoint Coriolis";
    sweep.push_back(s);
  }
  // one knob at a time from dt = 1/240 s, 20 iterations
  Setting s;
  for (const int interval : {2, 4}) {
    s.interval = interval;
    s.label = "H every " + std::to_string(interval) + " steps";
    sweep.push_back(s);
  }
  s = Setting{};
  s.tile = true;
  s.label = "use_tile_gemm";
  sweep.push_back(s);
  s = Setting{};
  s.fuse = false;
  s.label = "fuse_cholesky off";
  sweep.push_back(s);
  s = Setting{};
  s.warm = false;
  s.label = "warm starting off";
  sweep.push_back(s);
  for (const double tolerance : {0.0, 1e-3}) {
    s = Setting{};
    s.pgs_tolerance = tolerance;
    s.label = tolerance == 0 ? "pgs_tolerance 0" : "pgs_tolerance 1e-3";
    sweep.push_back(s);
  }
  return sweep;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool has_value = k + 1 < argc;
    if (arg == "--scene" && has_value) {
      o.scene = argv[++k];
    } else if (arg == "--side" && has_value) {
      o.side = std::atoi(argv[++k]);
    } else if (arg == "--threads" && has_value) {
      o.threads = std::atoi(argv[++k]);
    } else if (arg == "--out" && has_value) {
      o.out = argv[++k];
    } else if (arg == "--seconds" && has_value) {
      o.seconds.clear();
      std::stringstream list(argv[++k]);
      for (std::string t; std::getline(list, t, ',');) o.seconds.push_back(std::atof(t.c_str()));
    } else if (arg == "--no-contacts") {
      o.contacts = false;
    } else if (arg == "--no-progress") {
      o.progress = false;
    } else {
      fail("novaphy_sweep: unknown argument '", arg, "'");
    }
  }
  if (o.seconds.empty() || !std::is_sorted(o.seconds.begin(), o.seconds.end()) || !(o.seconds[0] > 0))
    fail("novaphy_sweep: --seconds must be increasing positive times, e.g. 1,10");
  for (const double t : o.seconds)
    if (std::abs(t * 60 - std::round(t * 60)) > 1e-9)
      fail("novaphy_sweep: every time in --seconds must be a multiple of 1/60 s, got ", t);
  if (o.side < 1) fail("novaphy_sweep: --side must be >= 1, got ", o.side);
  if (o.threads < 0) fail("novaphy_sweep: --threads must be >= 0 (0: all), got ", o.threads);
  return o;
}

std::string seconds_name(double t) {
  std::ostringstream os;
  os << t << "s";
  return os.str();
}

int sweep(const Options& o) {
  const Scene scene = scene_of(o);
  const Loaded loaded = load(scene);
  const Model& model = loaded.model;
  const State& start = loaded.start;
  std::vector<Setting> settings = settings_to_sweep();
  Setting reference;
  reference.dt = settings[0].dt;
  for (const Setting& s : settings) reference.dt = std::min(reference.dt, s.dt);
  reference.dt /= 16;
  reference.iterations = 200;
  reference.pgs_tolerance = 0;
  reference.label = "reference";

  int total = steps_to(o.seconds.back(), reference.dt), done = 0;
  for (const Setting& s : settings) total += steps_to(o.seconds.back(), s.dt);
  ProgressBar bar(total, "novaphy_sweep " + scene.name + ": steps", o.progress);
  const Result ref = run(model, scene, start, reference, o, bar, done);
  std::vector<std::vector<Scalar>> mujoco;
  if (!scene.contacts) mujoco = mujoco_rk4(loaded, reference.dt, o.seconds);

  Scalar total_mass = 0;
  for (const Scalar m : model.body_mass) total_mass += m;
  const std::string path = (o.out.empty() ? "sweep_" + scene.name : o.out) + ".csv";
  std::ofstream csv(path);
  csv << "scene,setting,dt,num_iterations,update_mass_matrix_interval,precision,use_tile_gemm,fuse_cholesky,"
         "use_warmstarting,coriolis_implicitness,pgs_tolerance,robot_steps_per_s,robot_seconds_per_s";
  for (const double t : o.seconds) csv << ",error_" << seconds_name(t);
  csv << ",energy_error_j_per_kg,max_penetration_m,max_limit_overshoot,diverged_steps";
  for (const double t : o.seconds) csv << ",mujoco_rk4_error_" << seconds_name(t);
  csv << "\n";
  csv.precision(6);
  auto row = [&](const Setting& s, const Result& r) {
    csv << scene.name << ",\"" << s.label << "\"," << s.dt << "," << s.iterations << "," << s.interval << ",float64,"
        << s.tile << "," << s.fuse << "," << s.warm << "," << s.coriolis << "," << s.pgs_tolerance << ","
        << r.robot_steps_per_s << "," << r.robot_steps_per_s * s.dt;
    for (size_t k = 0; k < o.seconds.size(); ++k) csv << "," << max_difference(r.q[k], ref.q[k]);
    csv << "," << std::abs(r.energy - ref.energy) / total_mass << "," << std::max<Scalar>(0, r.penetration) << ","
        << std::max<Scalar>(0, r.overshoot) << "," << r.diverged_steps;
    for (size_t k = 0; k < o.seconds.size(); ++k) {
      csv << ",";  // empty where the scene has contacts: no MuJoCo reference
      if (!mujoco.empty()) csv << max_difference(r.q[k], mujoco[k]);
    }
    csv << "\n";
  };
  row(reference, ref);
  for (const Setting& s : settings) row(s, run(model, scene, start, s, o, bar, done));
  if (!csv) fail("novaphy_sweep: cannot write ", path);
  std::printf("novaphy_sweep: %s, %zu settings and the reference (dt %g s, 200 iterations)%s -> %s\n",
              scene.name.c_str(), settings.size(), reference.dt,
              mujoco.empty() ? "" : ", errors also against MuJoCo's RK4", path.c_str());
  return 0;
}

}  // namespace
}  // namespace novaphy

int main(int argc, char** argv) {
  try {
    return novaphy::sweep(novaphy::parse(argc, argv));
  } catch (const novaphy::Error& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 2;
  }
}
