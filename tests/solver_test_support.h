// Shared helpers of the SolverFeatherstone tests (tests/engine/solver/, shapes_test.cpp, soft_contact_test.cpp): a
// finalized scene with its pipeline, contacts, solver, state and control, and the boxes, materials and settings they
// build on, and a world's share of a state.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"

namespace novaphy::solver_test {

inline constexpr Scalar kDt = 1.0 / 120;

// a finalized scene with its pipeline, contacts, solver, state and control
struct Scene {
  explicit Scene(const ModelBuilder& builder, const SolverFeatherstoneSettings& settings = {})
      : model(builder.finalize()),
        pipeline(model),
        contacts(pipeline.contacts()),
        solver(model, settings),
        state(model.state()),
        control(model.control()) {}

  void run(Scalar seconds, Scalar dt = kDt, const std::function<void()>& after_step = {}) {
    const int steps = static_cast<int>(std::lround(seconds / dt));
    for (int k = 0; k < steps; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, dt);
      if (after_step) after_step();
    }
  }
  Vec3 position(int body) const { return Eigen::Map<const Vec3>(&state.body_q[7 * body]); }
  Vec3 velocity(int body) const { return Eigen::Map<const Vec3>(&state.body_qd[6 * body]); }

  Model model;
  CollisionPipeline pipeline;
  Contacts contacts;
  SolverFeatherstone solver;
  State state;
  Control control;
};

// the entries of `field` (per-world rows of `width`) that belong to world w: bodies' by body_world, coordinates'
// and dofs' by their articulation's first body
template <typename T>
inline std::vector<T> world_rows(const Model& model, const std::vector<T>& field, int count, int w) {
  const int width = static_cast<int>(field.size()) / count;
  std::vector<T> out;
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = model.articulation(a);
    if (model.body_world[art.body(0)] != w) continue;
    int begin = 0, n = 0;
    if (count == model.body_count) {
      for (int l = 0; l < art.link_count(); ++l)
        out.insert(out.end(), field.begin() + width * art.body(l), field.begin() + width * (art.body(l) + 1));
      continue;
    }
    if (count == model.joint_coord_count) begin = art.q_begin(), n = art.coord_count();
    if (count == model.joint_dof_count) begin = art.qd_begin(), n = art.dof_count();
    out.insert(out.end(), field.begin() + begin, field.begin() + begin + n);
  }
  return out;
}

// the state's per-world arrays of world w, end to end
inline std::vector<Scalar> world_state(const Model& model, const State& s, int w) {
  std::vector<Scalar> out;
  for (const auto& [field, count] :
       {std::pair{&s.joint_q, model.joint_coord_count}, std::pair{&s.joint_qd, model.joint_dof_count},
        std::pair{&s.body_q, model.body_count}, std::pair{&s.body_qd, model.body_count},
        std::pair{&s.body_f, model.body_count}}) {
    const std::vector<Scalar> rows = world_rows(model, *field, count, w);
    out.insert(out.end(), rows.begin(), rows.end());
  }
  return out;
}

inline ShapeOptions material(Scalar mu, Scalar restitution = 0) {
  ShapeOptions options;
  options.mu = mu;
  options.restitution = restitution;
  return options;
}

inline int add_box(ModelBuilder& builder, const Vec3& position, Scalar half = 0.2, Scalar mass = 1, Scalar mu = 0.5) {
  const int body = builder.add_body(RigidBody::from_box(mass, Vec3::Constant(half)), Transform{position});
  builder.add_shape_box(body, Vec3::Constant(half), material(mu));
  return body;
}

inline SolverFeatherstoneSettings no_damping() {
  SolverFeatherstoneSettings settings;
  settings.angular_damping = 0;
  return settings;
}

// largest |x[k] - y[k]|
inline Scalar max_difference(const std::vector<Scalar>& x, const std::vector<Scalar>& y) {
  Scalar d = 0;
  for (size_t k = 0; k < x.size(); ++k) d = std::max(d, std::abs(x[k] - y[k]));
  return d;
}

// a pendulum: a box on a hinge about z, 2 m up (its hinge is joint 0)
inline ModelBuilder pendulum() {
  ModelBuilder robot;
  const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.parent_xform.p = Vec3(0, 2, 0);
  options.child_xform.p = Vec3(-0.25, 0, 0);
  robot.add_joint_revolute(-1, link, options);
  return robot;
}

// `count` worlds of one pendulum (four: one block): the blocks write each world's new state as they step it,
// all but the worlds they flag
inline ModelBuilder pendulum_worlds(Precision precision, int count = 4) {
  const ModelBuilder robot = pendulum();
  ModelBuilder worlds;
  worlds.set_precision(precision);
  worlds.replicate(robot, count);
  return worlds;
}

}  // namespace novaphy::solver_test
