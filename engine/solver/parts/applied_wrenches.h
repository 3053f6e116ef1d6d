// The wrenches a model applies to its bodies itself, beside the state's body_f: gravity compensation (MuJoCo's body
// gravcomp: a force -gravcomp m g through a body's centre of mass, g its world's gravity) and the actuators on sites
// (MuJoCo's site transmission: a thruster's force and torque, fixed in its body's frame). Written once here:
// SolverFeatherstone and the evaluations apply body_f with them added (applied_wrenches, at the state's
// coordinates), the solvers in maximal coordinates add them body by body (gravity_compensation,
// site_actuator_wrench).
#pragma once

#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// what the model applies itself: some body's gravity compensated, some actuator on a site
struct ModelWrenches {
  bool gravity_compensation = false;
  std::vector<int> site_actuators;      // the actuators on sites
  std::vector<int> site_articulations;  // the articulations their bodies are links of, ascending, once each

  static ModelWrenches of(const Model& model);
  bool any() const { return gravity_compensation || !site_actuators.empty(); }
};

// body b's compensating force (world frame, through its centre of mass)
Vec3 gravity_compensation(const Model& model, int b);

// the wrench [force; torque about the body's centre of mass] (world frame) of site actuator u at the command ctrl,
// its body at the pose `body_frame` (its origin's)
void site_actuator_wrench(const Model& model, int u, Scalar ctrl, const Transform& body_frame, Scalar wrench[6]);

// the wrenches body_f ([force at the centre of mass; torque] per body) with what the model applies added, into out
// (its storage kept from call to call): the compensation, and the site actuators' at the control's commands (none
// where control is null: inverse dynamics leaves actuators out) with their bodies where the state's joint_q puts
// them
void applied_wrenches(const Model& model, const ModelWrenches& wrenches, const State& state, const Control* control,
                      std::vector<Scalar>& out);

}  // namespace novaphy
