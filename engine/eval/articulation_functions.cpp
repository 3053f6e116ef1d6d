#include "engine/eval/articulation_functions.h"

#include <memory>

#include "engine/eval/eval.h"
#include "engine/model/error.h"

namespace novaphy {

namespace {

void assign(std::vector<Scalar>& dst, const VecX& src, const char* name) {
  if (static_cast<size_t>(src.size()) != dst.size())
    fail(name, " has ", src.size(), " entries, the joints need ", dst.size());
  for (Eigen::Index k = 0; k < src.size(); ++k) {
    if (!std::isfinite(src[k])) fail(name, "[", k, "] is not finite: ", src[k]);
    dst[k] = src[k];
  }
}

State articulation_state(const Model& model, const VecX& q, const VecX& qd) {
  State state = model.state();
  assign(state.joint_q, q, "q");
  assign(state.joint_qd, qd, "qd");
  return state;
}

bool same_joints(const std::vector<Joint>& a, const std::vector<Joint>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].type != b[i].type || a[i].axis != b[i].axis || a[i].parent != b[i].parent ||
        a[i].parent_to_joint.p != b[i].parent_to_joint.p ||
        a[i].parent_to_joint.q.coeffs() != b[i].parent_to_joint.q.coeffs())
      return false;
  return true;
}

bool same_bodies(const std::vector<RigidBody>& a, const std::vector<RigidBody>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].mass != b[i].mass || a[i].com != b[i].com || a[i].inertia != b[i].inertia) return false;
  return true;
}

// the articulation forward_dynamics last evaluated on this thread, with its model and kernels: a controller that
// asks about the same joints and bodies at every tick pays for the model and the kernels' set-up once
struct LastArticulation {
  std::vector<Joint> joints;
  std::vector<RigidBody> bodies;
  Vec3 gravity = Vec3::Zero();
  std::unique_ptr<Model> model;
  std::unique_ptr<ForwardDynamics> dynamics;
  State state;
  Control control;

  void use(const std::vector<Joint>& j, const std::vector<RigidBody>& b, const Vec3& g) {
    if (dynamics && gravity == g && same_joints(joints, j) && same_bodies(bodies, b)) return;
    std::unique_ptr<Model> made = std::make_unique<Model>(articulation_model(j, b, g));  // (throws on bad input)
    dynamics.reset();
    model = std::move(made);
    dynamics = std::make_unique<ForwardDynamics>(*model);
    state = model->state();
    control = model->control();
    joints = j, bodies = b, gravity = g;
  }
};

}  // namespace

Model articulation_model(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const Vec3& gravity) {
  if (joints.size() != bodies.size())
    fail("joints and bodies differ in length: ", joints.size(), " joints, ", bodies.size(), " bodies");
  if (joints.empty()) fail("joints is empty");
  ModelBuilder builder(gravity);
  for (size_t i = 0; i < bodies.size(); ++i) builder.add_body(bodies[i]);
  for (size_t i = 0; i < joints.size(); ++i) {
    const Joint& joint = joints[i];
    if (joint.parent >= static_cast<int>(i))
      fail("joint ", i, ": parent link ", joint.parent, " is not yet defined (parents come before children)");
    JointOptions options;
    options.parent_xform = joint.parent_to_joint;
    options.dof.axis = joint.axis;
    builder.add_joint(joint.type, joint.parent, static_cast<int>(i), options);
  }
  return builder.finalize();
}

Eigen::Matrix<Scalar, Eigen::Dynamic, 7, Eigen::RowMajor> forward_kinematics(const std::vector<Joint>& joints,
                                                                             const VecX& q) {
  const Model model = articulation_model(joints, std::vector<RigidBody>(joints.size()));
  State state = articulation_state(model, q, VecX::Zero(model.joint_dof_count));
  eval_fk(model, state);
  return Eigen::Map<const Eigen::Matrix<Scalar, Eigen::Dynamic, 7, Eigen::RowMajor>>(state.body_q.data(),
                                                                                     model.body_count, 7);
}

VecX inverse_dynamics(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q,
                      const VecX& qd, const VecX& qdd, const Vec3& gravity) {
  const Model model = articulation_model(joints, bodies, gravity);
  return eval_inverse_dynamics(model, articulation_state(model, q, qd), qdd);
}

MatX mass_matrix_crba(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q) {
  const Model model = articulation_model(joints, bodies);
  return eval_mass_matrix(model, articulation_state(model, q, VecX::Zero(model.joint_dof_count)));
}

VecX forward_dynamics(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q,
                      const VecX& qd, const VecX& tau, const Vec3& gravity) {
  thread_local LastArticulation last;
  last.use(joints, bodies, gravity);
  assign(last.state.joint_q, q, "q");
  assign(last.state.joint_qd, qd, "qd");
  assign(last.control.joint_f, tau, "tau");
  VecX qdd(last.model->joint_dof_count);
  last.dynamics->evaluate(last.state, last.control, qdd.data());
  return qdd;
}

}  // namespace novaphy
