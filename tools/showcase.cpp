// The main job (tools/run.sh): the robot of an MJCF file replicated into thousands of worlds and stepped
// for a few seconds by NovaPhy, then by MuJoCo 2.2.2 from the same file (one mjData a world, an OpenMP
// loop over the same threads). Prints both engines' robot-steps/s, where the robots' centres of mass
// ended in each, the largest difference of NovaPhy's forward dynamics from MuJoCo's at random states (the
// check of novaphy_validate), and draws a few worlds at a few times into a PNG.
//   novaphy_showcase [scene.xml] [--worlds N] [--seconds S | --steps N] [--mujoco-worlds N] [--threads N]
//                    [--float32] [--max-condim N] [--pgs-tolerance V] [--kick A] [--states N] [--picture file.png]
//                    [--frames N]
//                    [--no-progress] [--profile]
// Each world is the whole file (its floor too), contacts made where shapes touch (margin 0, MuJoCo's
// default), stepped at the file's timestep from the file's pose with random joint velocities of its own
// (the same in both engines; a free base hops and spins), so every world lands its own way. --kick
// scales those velocities (0: every world starts at rest).
// --profile prints NovaPhy's microseconds a step in collide and in each stage of step (the solver's
// profile_stages: each pass's wall time shared out among the stages as the threads' time went to them).
// --mujoco-worlds times MuJoCo on the first N worlds only (default 1024, or all when fewer; 0: not at all).
// Exit status: 0, 1 when the forward dynamics differ by more than 1e-9 (relative), 2 on an error.
#include <mujoco/mujoco.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/model/error.h"
#include "engine/model/model.h"
#include "engine/solver/solver_featherstone.h"
#include "tools/mujoco_oracle.h"
#include "tools/picture.h"
#include "tools/progress.h"

namespace novaphy {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";

struct Options {
  std::string scene = NOVAPHY_SCENE_DIR "/quadruped.xml";
  int worlds = 4096;
  double seconds = 3;
  int steps = -1;            // overrides seconds
  int mujoco_worlds = 1024;  // MuJoCo takes several times longer a world: timed on the first worlds only
  int threads = 0;           // 0: all
  bool float32 = false;
  double kick = 1;   // scales the first velocities
  int states = 100;  // forward-dynamics comparisons a scene
  std::string picture = "novaphy_showcase.png";
  int frames = 5;
  bool progress = true;
  int max_condim = 6;                                                 // the solver's setting of that name
  double pgs_tolerance = SolverFeatherstoneSettings{}.pgs_tolerance;  // the solver's setting of that name
  bool profile = false;
};

Options parse(int argc, char** argv) {
  Options o;
  bool scene_given = false;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool has_value = k + 1 < argc;
    if (arg == "--worlds" && has_value) {
      o.worlds = std::atoi(argv[++k]);
    } else if (arg == "--seconds" && has_value) {
      o.seconds = std::atof(argv[++k]);
    } else if (arg == "--steps" && has_value) {
      o.steps = std::atoi(argv[++k]);
    } else if (arg == "--mujoco-worlds" && has_value) {
      o.mujoco_worlds = std::atoi(argv[++k]);
    } else if (arg == "--threads" && has_value) {
      o.threads = std::atoi(argv[++k]);
    } else if (arg == "--kick" && has_value) {
      o.kick = std::atof(argv[++k]);
    } else if (arg == "--states" && has_value) {
      o.states = std::atoi(argv[++k]);
    } else if (arg == "--picture" && has_value) {
      o.picture = argv[++k];
    } else if (arg == "--frames" && has_value) {
      o.frames = std::atoi(argv[++k]);
    } else if (arg == "--max-condim" && has_value) {
      o.max_condim = std::atoi(argv[++k]);
    } else if (arg == "--pgs-tolerance" && has_value) {
      o.pgs_tolerance = std::atof(argv[++k]);
    } else if (arg == "--float32") {
      o.float32 = true;
    } else if (arg == "--profile") {
      o.profile = true;
    } else if (arg == "--no-progress") {
      o.progress = false;
    } else if (!arg.starts_with("--") && !scene_given) {
      o.scene = arg;
      scene_given = true;
    } else {
      fail("novaphy_showcase: unknown argument '", arg, "'");
    }
  }
  if (o.worlds < 1) fail("novaphy_showcase: --worlds must be >= 1, got ", o.worlds);
  if (o.steps < 0 && !(o.seconds > 0)) fail("novaphy_showcase: --seconds must be > 0, got ", o.seconds);
  if (o.steps == 0) fail("novaphy_showcase: --steps must be >= 1, got ", o.steps);
  if (o.threads < 0) fail("novaphy_showcase: --threads must be >= 0 (0: all), got ", o.threads);
  if (o.states < 0) fail("novaphy_showcase: --states must be >= 0, got ", o.states);
  if (o.frames < 2) fail("novaphy_showcase: --frames must be >= 2, got ", o.frames);
  if (o.mujoco_worlds < 0) fail("novaphy_showcase: --mujoco-worlds must be >= 0, got ", o.mujoco_worlds);
  o.mujoco_worlds = std::min(o.mujoco_worlds, o.worlds);
  return o;
}

std::string file_name(const std::string& path) { return std::filesystem::path(path).filename().string(); }

// the direction against gravity (+Z without gravity)
Vec3 up_against(const Vec3& gravity) { return gravity.norm() > 0 ? Vec3(-gravity.normalized()) : Vec3::UnitZ(); }

// "worlds 0-2", "world 0"
std::string first_worlds(int n) { return n == 1 ? "world 0" : "worlds 0-" + std::to_string(n - 1); }

// 1234567 -> "1,234,567"
std::string grouped(double x) {
  std::string digits = std::to_string(std::llround(x)), out;
  for (size_t k = 0; k < digits.size(); ++k) {
    if (k > 0 && (digits.size() - k) % 3 == 0) out += ',';
    out += digits[k];
  }
  return out;
}

// each world's first joint velocities in MuJoCo's coordinates (qvel), drawn from the world's own seed: a
// free joint hops (up against gravity, a little sideways) and spins; every other dof turns or slides a
// little, less the more of them there are (their velocities add up along a chain)
std::vector<mjtNum> kicks(const mjModel* m, int worlds, double scale) {
  const Vec3 up = up_against(Vec3(m->opt.gravity));
  int turning = 0;  // the dofs of joints other than free ones
  for (int j = 0; j < m->njnt; ++j) turning += m->jnt_type[j] == mjJNT_FREE ? 0 : m->jnt_type[j] == mjJNT_BALL ? 3 : 1;
  const double turn = 0.5 / std::sqrt(std::max(1, turning));
  std::vector<mjtNum> qvel(static_cast<size_t>(worlds) * m->nv, 0);
  for (int w = 0; w < worlds; ++w) {
    std::mt19937 rng(w);
    auto uniform = [&](double lo, double hi) { return scale * std::uniform_real_distribution<double>(lo, hi)(rng); };
    mjtNum* v = &qvel[static_cast<size_t>(w) * m->nv];
    for (int j = 0; j < m->njnt; ++j) {
      mjtNum* d = v + m->jnt_dofadr[j];
      if (m->jnt_type[j] == mjJNT_FREE) {
        Vec3 linear = uniform(1.5, 3.0) * up;
        for (int k = 0; k < 3; ++k) linear[k] += uniform(-0.5, 0.5);
        for (int k = 0; k < 3; ++k) d[k] = linear[k];
        for (int k = 3; k < 6; ++k) d[k] = uniform(-1, 1);  // (body frame)
      } else {
        for (int k = 0; k < (m->jnt_type[j] == mjJNT_BALL ? 3 : 1); ++k) d[k] = uniform(-turn, turn);
      }
    }
  }
  return qvel;
}

// the robot loaded once: MuJoCo's model of the file, NovaPhy's one world of it and the map between them
struct Robot {
  std::unique_ptr<mjModel, void (*)(mjModel*)> mujoco{nullptr, mj_deleteModel};
  ModelBuilder builder;
  MujocoImport import;
  Model model;
};

Robot load_robot(const std::string& path) {
  Robot robot;
  robot.mujoco.reset(load_mujoco_model(path));
  ImportOptions options;
  options.static_shapes = true;  // the file's floor in every world
  robot.import = import_mujoco_model(robot.builder, robot.mujoco.get(), options);
  robot.model = robot.builder.finalize();
  return robot;
}

// `worlds` copies of the robot; world w's dofs follow world w-1's in the robot's order (checked: the first
// velocities are written so)
Model replicate(const Robot& robot, int worlds, Precision precision) {
  ModelBuilder batch;
  batch.set_gravity(robot.builder.gravity());
  batch.set_precision(precision);
  batch.replicate(robot.builder, worlds);
  Model model = batch.finalize();
  const Model& one = robot.model;
  if (one.joint_dof_count != robot.mujoco->nv)
    fail("novaphy_showcase: NovaPhy's robot has ", one.joint_dof_count, " dofs, MuJoCo's ", robot.mujoco->nv);
  bool laid_out = model.joint_count == worlds * one.joint_count;
  for (int j = 0; laid_out && j < model.joint_count; ++j) {
    const int w = j / one.joint_count, k = j % one.joint_count;
    laid_out = model.joint_type[j] == one.joint_type[k] && model.body_world[model.joint_child[j]] == w &&
               model.joint_qd_start[j] == w * one.joint_dof_count + one.joint_qd_start[k];
  }
  if (!laid_out) fail("novaphy_showcase: the replicated worlds' joints are not laid out world after world");
  return model;
}

// the height (against gravity) of each world's centre of mass
std::vector<double> com_heights(const Model& model, const State& state) {
  const Vec3 up = up_against(model.gravity);
  std::vector<double> moment(model.world_count), mass(model.world_count);
  for (int b = 0; b < model.body_count; ++b) {
    const int w = model.body_world[b];
    if (w < 0) continue;
    const Vec3 com = Transform::from_array(&state.body_q[7 * b]).apply(Vec3(&model.body_com[3 * b]));
    moment[w] += model.body_mass[b] * com.dot(up);
    mass[w] += model.body_mass[b];
  }
  for (int w = 0; w < model.world_count; ++w) moment[w] /= mass[w];
  return moment;
}

double mean(const std::vector<double>& x, int n) {
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += x[k];
  return sum / n;
}

// the worlds drawn, one a row of the picture, and their solids at each frame's time
struct Film {
  std::vector<int> worlds;
  std::vector<int> frame_steps;
  std::vector<std::vector<std::vector<Solid>>> solids;  // [row][frame]

  Film(int world_count, int steps, int frames) {
    const int rows = std::min(3, world_count);
    for (int r = 0; r < rows; ++r) worlds.push_back(r * world_count / rows);
    // closer together early on, when the robots hop and land
    for (int f = 0; f < frames; ++f) {
      const double share = f / double(frames - 1);
      frame_steps.push_back(static_cast<int>(std::lround(share * share * steps)));
    }
    frame_steps.erase(std::unique(frame_steps.begin(), frame_steps.end()), frame_steps.end());  // (few steps)
    solids.resize(rows);
  }
  void record(const Model& model, const State& state, int step) {
    if (std::find(frame_steps.begin(), frame_steps.end(), step) == frame_steps.end()) return;
    for (size_t r = 0; r < worlds.size(); ++r) solids[r].push_back(world_solids(model, state, worlds[r]));
  }
};

struct NovaPhyRun {
  double seconds = 0;
  std::vector<double> heights;
  int diverged = 0;  // worlds with an articulation the divergence guard caught at some step
};

NovaPhyRun run_novaphy(const Model& model, const Robot& robot, const std::vector<mjtNum>& qvel, int steps, double dt,
                       const Options& o, Film& film) {
  CollisionOptions collision;
  collision.margin = 0;
  collision.num_threads = o.threads;
  CollisionPipeline pipeline(model, collision);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = o.threads;
  settings.max_condim = o.max_condim;
  settings.pgs_tolerance = o.pgs_tolerance;
  settings.profile_stages = o.profile;
  SolverFeatherstone solver(model, settings);
  // from the file's first keyframe (its commands held) where it has one, else its pose at rest; the kick on top
  const mjModel* m = robot.mujoco.get();
  const bool keyed = m->nkey > 0;
  State state = keyed ? model.state(model.keyframe_name[0]) : model.state();
  const Control control = keyed ? model.control(model.keyframe_name[0]) : model.control();
  const mjtNum* qpos = keyed ? m->key_qpos : m->qpos0;
  const int nv = robot.model.joint_dof_count;
  std::vector<Scalar> kick(nv);
  for (int w = 0; w < model.world_count; ++w) {
    robot.import.to_joint_qd(qpos, &qvel[static_cast<size_t>(w) * m->nv], kick.data());
    for (int k = 0; k < nv; ++k) state.joint_qd[w * nv + k] += kick[k];
  }
  std::vector<int> world_of(model.articulation_count);  // an articulation's world
  for (int a = 0; a < model.articulation_count; ++a) {
    const int joint = model.articulation_start[a];
    world_of[a] = joint < model.articulation_start[a + 1] ? std::max(0, model.body_world[model.joint_child[joint]]) : 0;
  }
  std::vector<std::uint8_t> diverged(model.world_count, 0);
  NovaPhyRun run;
  ProgressBar bar(steps, "NovaPhy      " + std::to_string(model.world_count) + " worlds", o.progress);
  film.record(model, state, 0);
  double collide_seconds = 0;
  for (int s = 0; s < steps; ++s) {
    const Clock::time_point start = Clock::now();
    pipeline.collide(state, contacts);
    collide_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    solver.step(state, state, control, contacts, dt);
    run.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    for (int a = 0; a < model.articulation_count; ++a) diverged[world_of[a]] |= solver.diverged()[a];
    film.record(model, state, s + 1);
    bar.update(s + 1);
  }
  run.heights = com_heights(model, state);
  for (const std::uint8_t flag : diverged) run.diverged += flag;
  if (o.profile) {
    const SolverStageSeconds& t = solver.stage_seconds();
    const double us = 1e6 / steps;
    std::printf(
        "profile, microseconds a step: collide %.1f, dynamics %.1f, limit rows %.1f, contact rows %.1f, solve %.1f, "
        "integrate %.1f\n",
        collide_seconds * us, t.dynamics * us, t.limit_rows * us, t.contact_rows * us, t.solve * us, t.integrate * us);
  }
  return run;
}

struct MujocoRun {
  double seconds = 0;
  std::vector<double> heights;
  int warnings = 0;
  std::string first_warning;
};

// MuJoCo's warnings while it steps (a world gone unstable, which it resets), counted rather than printed
std::atomic<int> mujoco_warnings{0};
std::mutex mujoco_warning_mutex;
std::string mujoco_first_warning;
void count_mujoco_warning(const char* message) {
  if (mujoco_warnings++ > 0) return;
  const std::lock_guard<std::mutex> lock(mujoco_warning_mutex);
  mujoco_first_warning = message;
}

MujocoRun run_mujoco(const mjModel* m, const std::vector<mjtNum>& qvel, int worlds, int steps, const Options& o) {
  std::vector<std::unique_ptr<mjData, void (*)(mjData*)>> data;
  for (int w = 0; w < worlds; ++w) {
    data.emplace_back(mj_makeData(m), mj_deleteData);
    if (m->nkey > 0) mj_resetDataKeyframe(m, data.back().get(), 0);  // its pose, velocities and commands
    for (int k = 0; k < m->nv; ++k) data.back()->qvel[k] += qvel[static_cast<size_t>(w) * m->nv + k];
  }
  const int threads = o.threads > 0 ? o.threads : omp_get_max_threads();
  MujocoRun run;
  mujoco_warnings = 0;
  mju_user_warning = count_mujoco_warning;
  ProgressBar bar(steps, "MuJoCo 2.2.2 " + std::to_string(worlds) + " worlds", o.progress);
  for (int s = 0; s < steps; ++s) {
    const Clock::time_point start = Clock::now();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int w = 0; w < worlds; ++w) mj_step(m, data[w].get());
    run.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    bar.update(s + 1);
  }
  mju_user_warning = nullptr;
  run.warnings = mujoco_warnings;
  run.first_warning = mujoco_first_warning;
  const Vec3 up = up_against(Vec3(m->opt.gravity));
  for (auto& d : data) {
    mj_kinematics(m, d.get());
    double moment = 0, mass = 0;
    for (int b = 1; b < m->nbody; ++b) {
      moment += m->body_mass[b] * Vec3(d->xipos + 3 * b).dot(up);
      mass += m->body_mass[b];
    }
    run.heights.push_back(moment / mass);
  }
  return run;
}

// novaphy_validate's check on the scene and its two defaults: the largest relative difference (-1: none ran)
Scalar validate(const std::string& scene, int states) {
  std::vector<std::string> paths{scene};
  for (const std::string& other : {std::string(kHumanoid), std::string(NOVAPHY_SCENE_DIR "/chain15.xml")}) {
    std::error_code error;
    if (std::filesystem::exists(other) && !std::filesystem::equivalent(other, scene, error)) paths.push_back(other);
  }
  Scalar worst = -1;
  std::string names;
  std::mt19937 rng(2026);
  for (const std::string& path : paths) {
    try {
      MujocoOracle oracle(path);
      OracleErrors e;
      for (int s = 0; s < states; ++s) e.accumulate(oracle.compare_random_state(rng));
      worst = std::max(worst, e.max());
      names += (names.empty() ? "" : ", ") + file_name(path);
    } catch (const Error& error) {
      std::printf("validation: %s skipped: %s\n", file_name(path).c_str(), error.what());
    }
  }
  if (worst < 0) return worst;
  std::printf(
      "validation (forward dynamics at %d random states of %s; contacts and limits off): largest relative "
      "difference NovaPhy vs MuJoCo 2.2.2: %.3e (%s 1e-9)\n",
      states, names.c_str(), worst, worst <= 1e-9 ? "within" : "ABOVE");
  return worst;
}

void draw(const Film& film, const Vec3& gravity, const std::string& path) {
  constexpr int kWidth = 280, kHeight = 210, kGutter = 4;
  const int rows = static_cast<int>(film.worlds.size()), columns = static_cast<int>(film.frame_steps.size());
  Image image(columns * (kWidth + kGutter) + kGutter, rows * (kHeight + kGutter) + kGutter);
  for (int r = 0; r < rows; ++r) {
    const Camera camera = frame_solids(film.solids[r], gravity);
    for (int f = 0; f < columns; ++f)
      draw_panel(image, kGutter + f * (kWidth + kGutter), kGutter + r * (kHeight + kGutter), kWidth, kHeight,
                 film.solids[r][f], camera);
  }
  write_png(image, path);
}

int run(const Options& o) {
  const Robot robot = load_robot(o.scene);
  const mjModel* m = robot.mujoco.get();
  const double dt = m->opt.timestep;
  const int steps = o.steps > 0 ? o.steps : std::max(1, static_cast<int>(std::lround(o.seconds / dt)));
  const Model model = replicate(robot, o.worlds, o.float32 ? Precision::Float32 : Precision::Float64);
  const std::vector<mjtNum> qvel = kicks(m, o.worlds, o.kick);
  const int threads = o.threads > 0 ? o.threads : omp_get_max_threads();
  std::printf("novaphy_showcase: %s, %d worlds of %d bodies and %d dofs, %d steps of %g ms (%g s), %s, %d thread%s\n",
              file_name(o.scene).c_str(), o.worlds, robot.model.body_count, robot.model.joint_dof_count, steps,
              dt * 1e3, steps * dt, o.float32 ? "float32" : "float64", threads, threads == 1 ? "" : "s");
  const std::string start =
      m->nkey > 0 ? "its keyframe '" + robot.model.keyframe_name[0] + "' (commands held)" : "the file's pose";
  if (o.kick != 0) std::printf("each world starts from %s with its own random joint velocities\n", start.c_str());
  if (o.kick == 0) std::printf("each world starts from %s\n", start.c_str());
  for (const std::string& warning : robot.import.warnings) std::printf("import: %s\n", warning.c_str());
  std::fflush(stdout);

  Film film(o.worlds, steps, o.frames);
  const NovaPhyRun nova = run_novaphy(model, robot, qvel, steps, dt, o, film);
  MujocoRun mujoco;
  if (o.mujoco_worlds > 0) mujoco = run_mujoco(m, qvel, o.mujoco_worlds, steps, o);

  const double nova_rate = o.worlds * double(steps) / nova.seconds;
  std::printf("%-14s %7s %10s %15s\n", "engine", "worlds", "time (s)", "robot-steps/s");
  std::printf("%-14s %7d %10.3f %15s\n", "NovaPhy", o.worlds, nova.seconds, grouped(nova_rate).c_str());
  if (o.mujoco_worlds > 0) {
    const double mujoco_rate = o.mujoco_worlds * double(steps) / mujoco.seconds;
    std::printf("%-14s %7d %10.3f %15s\n", "MuJoCo 2.2.2", o.mujoco_worlds, mujoco.seconds,
                grouped(mujoco_rate).c_str());
    std::printf("NovaPhy / MuJoCo 2.2.2: %.3gx the robot-steps/s on the same %d thread%s\n", nova_rate / mujoco_rate,
                threads, threads == 1 ? "" : "s");
    std::printf("centre of mass height at %g s, mean over %s: NovaPhy %.4f m, MuJoCo %.4f m\n", steps * dt,
                first_worlds(o.mujoco_worlds).c_str(), mean(nova.heights, o.mujoco_worlds),
                mean(mujoco.heights, o.mujoco_worlds));
    if (mujoco.warnings > 0)
      std::printf("MuJoCo 2.2.2 warned %d times, first: %s\n", mujoco.warnings, mujoco.first_warning.c_str());
  }
  std::printf("NovaPhy worlds flagged diverged: %d of %d\n", nova.diverged, o.worlds);
  std::fflush(stdout);

  const Scalar worst = o.states > 0 ? validate(o.scene, o.states) : -1;

  draw(film, model.gravity, o.picture);
  std::string rows, times;
  for (const int w : film.worlds) rows += (rows.empty() ? "" : ", ") + std::to_string(w);
  for (const int s : film.frame_steps) {
    char t[32];
    std::snprintf(t, sizeof(t), "%g", s * dt);
    times += (times.empty() ? "" : ", ") + std::string(t);
  }
  std::printf("picture: %s (rows: worlds %s; columns: t = %s s)\n", o.picture.c_str(), rows.c_str(), times.c_str());
  return worst > 1e-9 ? 1 : 0;
}

}  // namespace
}  // namespace novaphy

int main(int argc, char** argv) {
  try {
    return novaphy::run(novaphy::parse(argc, argv));
  } catch (const novaphy::Error& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 2;
  }
}
