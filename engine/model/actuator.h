// MuJoCo's affine actuator on a Revolute or Prismatic joint or a fixed tendon (a motor, position and velocity
// servos, a general actuator of fixed gain and affine bias), written once for the step and the whole-model
// evaluations; on a tendon its length and velocity stand for q and qd (engine/model/tendon.h):
//   force = clamp(gain clamp(ctrl, ctrl range) + bias0 + bias1 gear q + bias2 gear qd, force range)
// and the joint takes gear force. Split for the step: the joint force at (q, qd) is
//   force - stiffness q - damping qd
// whose stiffness and damping the step integrates implicitly, as a joint's spring and damper; an actuator
// whose force is past its force range is a constant force at the limit (exact there).
#pragma once

#include <algorithm>

#include "engine/model/model.h"

namespace novaphy {

struct ActuatorForce {
  Scalar force = 0, stiffness = 0, damping = 0;
};

// an actuator's numbers, as actuator_force reads them (the step reads a table of the distinct ones: a model of
// replicated robots has few)
struct ActuatorParams {
  Scalar gear = 0, gain = 0, bias[3] = {}, ctrl_lower = 0, ctrl_upper = 0, force_lower = 0, force_upper = 0;
};
inline ActuatorParams actuator_params(const Model& model, int u) {
  return {model.actuator_gear[u],
          model.actuator_gain[u],
          {model.actuator_bias[3 * u], model.actuator_bias[3 * u + 1], model.actuator_bias[3 * u + 2]},
          model.actuator_ctrl_lower[u],
          model.actuator_ctrl_upper[u],
          model.actuator_force_lower[u],
          model.actuator_force_upper[u]};
}

// an actuator of numbers p at the coordinate q and velocity qd of its joint
inline ActuatorForce actuator_force(const ActuatorParams& p, Scalar ctrl, Scalar q, Scalar qd) {
  const Scalar gear = p.gear;
  const Scalar* bias = p.bias;
  const Scalar command = std::clamp(ctrl, p.ctrl_lower, p.ctrl_upper);
  const Scalar constant = p.gain * command + bias[0];
  const Scalar force = constant + bias[1] * gear * q + bias[2] * gear * qd;
  const Scalar clamped = std::clamp(force, p.force_lower, p.force_upper);
  if (clamped != force) return {gear * clamped, 0, 0};
  return {gear * constant, 0 - gear * gear * bias[1], 0 - gear * gear * bias[2]};
}
// actuator u at the coordinate q and velocity qd of its joint
inline ActuatorForce actuator_force(const Model& model, int u, Scalar ctrl, Scalar q, Scalar qd) {
  return actuator_force(actuator_params(model, u), ctrl, q, qd);
}
// the joint force of actuator u at (q, qd)
inline Scalar actuator_joint_force(const Model& model, int u, Scalar ctrl, Scalar q, Scalar qd) {
  const ActuatorForce a = actuator_force(model, u, ctrl, q, qd);
  return a.force - a.stiffness * q - a.damping * qd;
}

}  // namespace novaphy
