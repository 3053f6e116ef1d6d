// MuJoCo's affine actuator on a Revolute or Prismatic joint or a fixed tendon (a motor, position and velocity
// servos, a general actuator of fixed gain and affine bias), written once for the step and the whole-model
// evaluations; on a tendon its length and velocity stand for q and qd (engine/parts/tendon.h):
//   force = clamp(gain clamp(ctrl, ctrl range) + bias0 + bias1 gear q + bias2 gear qd, force range)
// and the joint takes gear force. Split for the step: the joint force at (q, qd) is
//   force - stiffness q - damping qd
// whose stiffness and damping the step integrates implicitly, as a joint's spring and damper; an actuator
// whose force is past its force range is a constant force at the limit (exact there).
#pragma once

#include <algorithm>

#include "engine/model.h"

namespace novaphy {

struct ActuatorForce {
  Scalar force = 0, stiffness = 0, damping = 0;
};

// actuator u at the coordinate q and velocity qd of its joint
inline ActuatorForce actuator_force(const Model& model, int u, Scalar ctrl, Scalar q, Scalar qd) {
  const Scalar gear = model.actuator_gear[u];
  const Scalar* bias = &model.actuator_bias[3 * u];
  const Scalar command = std::clamp(ctrl, model.actuator_ctrl_lower[u], model.actuator_ctrl_upper[u]);
  const Scalar constant = model.actuator_gain[u] * command + bias[0];
  const Scalar force = constant + bias[1] * gear * q + bias[2] * gear * qd;
  const Scalar clamped = std::clamp(force, model.actuator_force_lower[u], model.actuator_force_upper[u]);
  if (clamped != force) return {gear * clamped, 0, 0};
  return {gear * constant, 0 - gear * gear * bias[1], 0 - gear * gear * bias[2]};
}

// the joint force of actuator u at (q, qd)
inline Scalar actuator_joint_force(const Model& model, int u, Scalar ctrl, Scalar q, Scalar qd) {
  const ActuatorForce a = actuator_force(model, u, ctrl, q, qd);
  return a.force - a.stiffness * q - a.damping * qd;
}

}  // namespace novaphy
