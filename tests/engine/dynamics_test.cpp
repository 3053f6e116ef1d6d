// ForwardDynamics (engine/dynamics.h): the step's batched kernels made once for a model, evaluated again and
// again, against the reference kernels' CRBA + Cholesky (eval_forward_dynamics) on MuJoCo's humanoid.
#include "engine/dynamics.h"

#include <gtest/gtest.h>

#include "engine/mjcf_import.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

Model humanoid(Precision precision, int worlds) {
  ModelBuilder robot;
  robot.add_mjcf(NOVAPHY_HUMANOID_XML);
  ModelBuilder batch(robot.gravity());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

// a state of every world its own: coordinates, velocities, forces and applied wrenches
void random_state(const Model& model, State& state, Control& control) {
  for (size_t k = 0; k < state.joint_qd.size(); ++k) state.joint_qd[k] = std::sin(1.7 * k) * 2;
  for (size_t k = 0; k < state.joint_q.size(); ++k) state.joint_q[k] += 0.3 * std::cos(0.9 * k);
  for (int j = 0; j < model.joint_count; ++j)
    if (model.joint_type[j] == static_cast<int>(JointType::Free)) {
      Scalar* quat = &state.joint_q[model.joint_q_start[j] + 3];
      Eigen::Map<Quat>(quat).normalize();
    }
  for (size_t k = 0; k < control.joint_f.size(); ++k) control.joint_f[k] = std::cos(0.4 * k);
  for (size_t k = 0; k < state.body_f.size(); ++k) state.body_f[k] = 0.1 * std::sin(0.3 * k);
}

TEST(ForwardDynamics, MatchesTheReferenceKernelsAndRepeatsItsBits) {
  for (const Precision precision : {Precision::Float64, Precision::Float32}) {
    const Model model = humanoid(precision, 3);
    State state = model.state();
    Control control = model.control();
    random_state(model, state, control);
    const VecX expected = eval_forward_dynamics(model, state, control);
    ForwardDynamics dynamics(model);
    VecX first(model.joint_dof_count), again(model.joint_dof_count);
    dynamics.evaluate(state, control, first.data());
    dynamics.evaluate(state, control, again.data());
    EXPECT_EQ(first, again);
    const Scalar scale = expected.cwiseAbs().maxCoeff();
    EXPECT_LT((first - expected).cwiseAbs().maxCoeff() / scale, precision == Precision::Float64 ? 1e-12 : 1e-4);
    // another state through the same object: its own accelerations
    state.joint_qd[0] += 1;
    dynamics.evaluate(state, control, again.data());
    EXPECT_LT((again - eval_forward_dynamics(model, state, control)).cwiseAbs().maxCoeff() / scale,
              precision == Precision::Float64 ? 1e-12 : 1e-4);
  }
}

TEST(ForwardDynamics, ChecksItsArguments) {
  const Model model = humanoid(Precision::Float64, 1);
  ForwardDynamics dynamics(model);
  State state = model.state();
  Control control = model.control();
  VecX qdd(model.joint_dof_count);
  state.joint_qd[4] = std::nan("");
  EXPECT_NOVAPHY_ERROR(dynamics.evaluate(state, control, qdd.data()), "joint_qd[4] is not finite");
  state.joint_qd[4] = 0;
  control.joint_f.resize(3);
  EXPECT_NOVAPHY_ERROR(dynamics.evaluate(state, control, qdd.data()), "joint_f");
}

}  // namespace
}  // namespace novaphy
