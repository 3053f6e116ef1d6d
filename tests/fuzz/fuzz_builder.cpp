// libFuzzer target: a random sequence of ModelBuilder calls (valid and invalid arguments; the maximal-coordinate
// joints among them), then finalize, forward dynamics and a few steps with contacts by one of the three solvers. Errors
// must be novaphy::Error; a crash, a sanitizer report or any other exception is a finding.
#include <cstdint>

#include "engine/eval/eval.h"
#include "engine/model/builder.h"
#include "engine/model/error.h"
#include "engine/solver/semi_implicit/solver_semi_implicit.h"
#include "engine/solver/solver_featherstone.h"
#include "engine/solver/xpbd/solver_xpbd.h"
#include "fuzz_support.h"

using namespace novaphy;

namespace {

void build_step(FuzzedDataProvider& data, ModelBuilder& builder) {
  const int bodies = builder.body_count(), joints = builder.joint_count();
  switch (data.ConsumeIntegralInRange(0, 10)) {
    case 0: {
      RigidBody body;
      body.mass = data.ConsumeBool() ? data.ConsumeFloatingPointInRange<Scalar>(0.1, 5) : fuzz::number(data);
      body.com = data.ConsumeBool() ? Vec3::Zero() : fuzz::vec3(data);
      if (data.ConsumeBool())
        body.inertia = Vec3(fuzz::number(data), fuzz::number(data), fuzz::number(data)).asDiagonal();
      builder.add_body(body, fuzz::transform(data));
      break;
    }
    case 1: {
      JointOptions options;
      options.parent_xform = fuzz::transform(data);
      options.child_xform = fuzz::transform(data);
      options.dof.axis = data.ConsumeBool() ? Vec3::UnitZ() : fuzz::vec3(data);
      if (data.ConsumeBool())
        options.dof.limit_lower = fuzz::number(data), options.dof.limit_upper = fuzz::number(data);
      if (data.ConsumeBool()) options.dof.damping = fuzz::number(data), options.dof.stiffness = fuzz::number(data);
      if (data.ConsumeBool()) options.dof.target_ke = fuzz::number(data), options.dof.target_kd = fuzz::number(data);
      if (data.ConsumeBool()) {  // soft limits and dry friction, in range or not
        options.dof.frictionloss = fuzz::number(data);
        options.dof.limit_solref = {fuzz::number(data), fuzz::number(data)};
        options.dof.friction_solref = {fuzz::number(data), fuzz::number(data)};
        options.dof.limit_solimp = {fuzz::number(data), fuzz::number(data), fuzz::number(data), fuzz::number(data),
                                    fuzz::number(data)};
      }
      const auto type = static_cast<JointType>(data.ConsumeIntegralInRange(0, 4));
      builder.add_joint(type, data.ConsumeIntegralInRange(-2, bodies), data.ConsumeIntegralInRange(-1, bodies),
                        options);
      break;
    }
    case 2: {
      ShapeOptions options;
      options.xform = fuzz::transform(data);
      if (data.ConsumeBool()) options.mu = fuzz::number(data), options.restitution = fuzz::number(data);
      if (data.ConsumeBool()) {  // MuJoCo's softness, in range or not
        options.solref = {fuzz::number(data), fuzz::number(data)};
        options.solimp = {fuzz::number(data), fuzz::number(data), fuzz::number(data), fuzz::number(data),
                          fuzz::number(data)};
        options.margin = fuzz::number(data);
      }
      const int body = data.ConsumeIntegralInRange(-2, bodies);
      const Scalar size = data.ConsumeBool() ? data.ConsumeFloatingPointInRange<Scalar>(0.01, 1) : fuzz::number(data);
      switch (data.ConsumeIntegralInRange(0, 5)) {
        case 0: builder.add_shape_box(body, Vec3(size, size, fuzz::number(data)), options); break;
        case 1: builder.add_shape_sphere(body, size, options); break;
        case 2: builder.add_shape_cylinder(body, size, fuzz::number(data), options); break;
        case 3: builder.add_shape_ellipsoid(body, Vec3(size, fuzz::number(data), size), options); break;
        case 4: {  // a mesh of a few points, flat, repeated or not finite at times
          std::vector<Vec3> points(data.ConsumeIntegralInRange(0, 12));
          for (Vec3& p : points) p = data.ConsumeBool() ? size * fuzz::vec3(data) : Vec3(size, 0, -size);
          builder.add_shape_mesh(body, builder.add_mesh(points), options);
          break;
        }
        default: builder.add_shape_capsule(body, size, fuzz::number(data), options); break;
      }
      break;
    }
    case 3: builder.add_plane(data.ConsumeBool() ? Vec3::UnitY() : fuzz::vec3(data), fuzz::number(data)); break;
    case 4: {
      const int first = data.ConsumeIntegralInRange(-1, joints);
      std::vector<int> list;
      for (int k = 0, n = data.ConsumeIntegralInRange(0, 4); k < n; ++k) list.push_back(first + k);
      builder.add_articulation(list);
      break;
    }
    case 5:
      builder.add_motor(data.ConsumeIntegralInRange(-1, joints), fuzz::number(data), fuzz::number(data),
                        fuzz::number(data));
      break;
    case 6: builder.set_gravity(fuzz::vec3(data)); break;
    case 7: {  // a fixed tendon over a few joints (of one articulation or several, fixed or floating), an actuator;
      std::vector<int> list;
      std::vector<Scalar> coefs;
      for (int k = 0, n = data.ConsumeIntegralInRange(0, 3); k < n; ++k) {
        list.push_back(data.ConsumeIntegralInRange(-1, joints));
        coefs.push_back(fuzz::number(data));
      }
      TendonOptions options;
      if (data.ConsumeBool()) options.stiffness = fuzz::number(data), options.damping = fuzz::number(data);
      if (data.ConsumeBool()) options.limit_lower = fuzz::number(data), options.limit_upper = fuzz::number(data);
      if (data.ConsumeBool()) options.limit_solref = {fuzz::number(data), fuzz::number(data)};
      // or a spatial one: a path of any elements on any bodies, any frames and sizes
      std::vector<TendonPathElement> path;
      for (int k = 0, n = data.ConsumeIntegralInRange(0, 5); k < n; ++k)
        path.push_back({static_cast<TendonPathKind>(data.ConsumeIntegralInRange(0, 5)),
                        data.ConsumeIntegralInRange(-2, bodies), fuzz::transform(data), fuzz::number(data)});
      const int tendon =
          path.empty() ? builder.add_tendon(list, coefs, options) : builder.add_spatial_tendon(path, options);
      if (data.ConsumeBool()) builder.add_tendon_actuator(tendon);
      break;
    }
    case 8: {  // a maximal-coordinate joint: Distance, D6 (a few axes, any directions) or Cable
      JointOptions options;
      options.parent_xform = fuzz::transform(data);
      options.child_xform = fuzz::transform(data);
      const int parent = data.ConsumeIntegralInRange(-2, bodies), child = data.ConsumeIntegralInRange(-1, bodies);
      switch (data.ConsumeIntegralInRange(0, 2)) {
        case 0:
          builder.add_joint_distance(parent, child, options, fuzz::number(data), fuzz::number(data),
                                     fuzz::number(data));
          break;
        case 1: {
          std::vector<JointDofConfig> axes[2];
          for (auto& list : axes)
            for (int k = 0, n = data.ConsumeIntegralInRange(0, 4); k < n; ++k) {
              JointDofConfig dof;
              dof.axis = data.ConsumeBool() ? Vec3::Unit(data.ConsumeIntegralInRange(0, 2)) : fuzz::vec3(data);
              if (data.ConsumeBool()) dof.limit_lower = fuzz::number(data), dof.limit_upper = fuzz::number(data);
              if (data.ConsumeBool()) dof.target_ke = fuzz::number(data), dof.target_kd = fuzz::number(data);
              list.push_back(dof);
            }
          builder.add_joint_d6(parent, child, options, axes[0], axes[1], fuzz::number(data), fuzz::number(data));
          break;
        }
        default: builder.add_joint_cable(parent, child, options, fuzz::number(data), fuzz::number(data)); break;
      }
      break;
    }
    case 9: {  // what the model applies itself: gravity compensation, a thruster on a site, a fluid
      const int body = data.ConsumeIntegralInRange(-1, bodies);
      switch (data.ConsumeIntegralInRange(0, 2)) {
        case 0: builder.set_body_gravcomp(body, fuzz::number(data)); break;
        case 1: {
          const Transform site{fuzz::vec3(data),
                               Quat(fuzz::number(data), fuzz::number(data), fuzz::number(data), fuzz::number(data))};
          ActuatorOptions options;
          if (data.ConsumeBool()) options.bias = fuzz::vec3(data), options.gear = fuzz::number(data);
          builder.add_site_actuator(body, site,
                                    {fuzz::number(data), fuzz::number(data), fuzz::number(data), fuzz::number(data),
                                     fuzz::number(data), fuzz::number(data)},
                                    options);
          break;
        }
        default: builder.set_fluid(fuzz::number(data), fuzz::number(data), fuzz::vec3(data)); break;
      }
      break;
    }
    default: builder.add_ground_plane(fuzz::number(data)); break;
  }
}

// a few steps of `solver` (its settings fuzzed by `settings`)
template <typename Solver, typename Settings>
void steps(FuzzedDataProvider& data, const Model& model, State& state, const Control& control,
           const Settings& settings) {
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  Solver solver(model);
  solver.settings = settings;
  for (int k = 0; k < 3; ++k) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, data.ConsumeBool() ? 0.01 : fuzz::number(data));
  }
}

void simulate(FuzzedDataProvider& data, const Model& model) {
  State state = model.state();
  for (Scalar& q : state.joint_qd) q = data.ConsumeFloatingPointInRange<Scalar>(-5, 5);
  Control control = model.control();
  for (Scalar& f : control.joint_f) f = fuzz::number(data);
  for (Scalar& u : control.actuator_ctrl) u = data.ConsumeBool() ? data.ConsumeFloatingPointInRange<Scalar>(-5, 5) : 0;
  eval_forward_dynamics(model, state, control,
                        data.ConsumeBool() ? ForwardDynamicsMethod::Aba : ForwardDynamicsMethod::Crba);
  if (model.articulation_count == 0) return;
  switch (data.ConsumeIntegralInRange(0, 2)) {
    case 0: {
      SolverFeatherstoneSettings settings;
      settings.num_iterations = data.ConsumeIntegralInRange(-1, 30);
      settings.erp = fuzz::number(data);
      steps<SolverFeatherstone>(data, model, state, control, settings);
      break;
    }
    case 1: {
      SolverSemiImplicitSettings settings;
      settings.num_iterations = data.ConsumeIntegralInRange(-1, 30);
      settings.erp = fuzz::number(data);
      steps<SolverSemiImplicit>(data, model, state, control, settings);
      break;
    }
    default: {
      SolverXPBDSettings settings;
      settings.iterations = data.ConsumeIntegralInRange(-1, 8);
      settings.substeps = data.ConsumeIntegralInRange(-1, 8);
      settings.joint_linear_compliance = fuzz::number(data);
      steps<SolverXPBD>(data, model, state, control, settings);
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  ModelBuilder builder;
  for (int k = 0, n = data.ConsumeIntegralInRange(0, 40); k < n; ++k) {
    try {
      build_step(data, builder);
    } catch (const Error&) {
    }
  }
  try {
    simulate(data, builder.finalize());
  } catch (const Error&) {
  }
  return 0;
}
