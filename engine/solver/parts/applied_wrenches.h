// The wrenches a model applies to its bodies itself, beside the state's body_f: gravity compensation (MuJoCo's body
// gravcomp: a force -gravcomp m g through a body's centre of mass, g its world's gravity), the actuators on sites
// (MuJoCo's site transmission: a thruster's force and torque, fixed in its body's frame), the fluid's forces
// (MuJoCo's inertia-box model: viscous and quadratic drag on the box of the body's inertia, or its ellipsoid model on a
// body's fluid ellipsoids: added mass, drag, Kutta and Magnus lift) and the forces along
// spatial tendons (their springs, dampers and actuators, pulling their paths' sites and wraps:
// engine/model/spatial_tendon.h). Written once here: SolverFeatherstone and the evaluations apply body_f with them
// added (applied_wrenches, at the state's coordinates and velocities), the solvers in maximal coordinates add them
// body by body (gravity_compensation, site_actuator_wrench, fluid_wrench; they take no tendons).
#pragma once

#include <vector>

#include "engine/model/model.h"
#include "engine/model/spatial_tendon.h"
#include "kernels/articulation.h"

namespace novaphy {

// what the model applies itself: some body's gravity compensated, some actuator on a site, a fluid
struct ModelWrenches {
  bool gravity_compensation = false;
  bool fluid = false;                // the model's fluid density or viscosity is > 0
  std::vector<int> site_actuators;   // the actuators on sites
  std::vector<int> spatial_tendons;  // the spatial tendons
  // the actuators on spatial_tendons[k]: tendon_actuators[tendon_actuator_start[k] .. [k + 1])
  std::vector<int> tendon_actuator_start, tendon_actuators;
  // the articulations whose bodies' poses and velocities they need (site actuators, a fluid, spatial tendons),
  // ascending, once each; those of the fluid's bodies
  std::vector<int> moved_articulations, fluid_articulations;
  // applied_wrenches' scratch, kept from call to call (a step allocates nothing): an articulation's kinematics, the
  // bodies' poses and velocities (body_q, body_qd), a tendon's pieces
  ArticulationScratch scratch;
  State bodies;
  std::vector<TendonSpan> spans;

  static ModelWrenches of(const Model& model);
  // something to apply (`actuated`: with the actuators' commands; inverse dynamics has none)
  bool any(bool actuated = true) const {
    return gravity_compensation || fluid || !spatial_tendons.empty() || (actuated && !site_actuators.empty());
  }
};

// the model's bodies move through a fluid: its density or viscosity is > 0
inline bool has_fluid(const Model& model) { return model.fluid_density > 0 || model.fluid_viscosity > 0; }

// body b's compensating force (world frame, through its centre of mass)
Vec3 gravity_compensation(const Model& model, int b);

// the wrench [force; torque about the body's centre of mass] (world frame) of site actuator u at the command ctrl,
// its body at the pose `body_frame` (its origin's)
void site_actuator_wrench(const Model& model, int u, Scalar ctrl, const Transform& body_frame, Scalar wrench[6]);

// the fluid's wrench [force; torque] (world frame, about its centre of mass) on body b at the pose `body_frame`, its
// centre of mass moving at v and turning at w (world frame): its fluid ellipsoids', else its inertia box's; zero for
// a body of no mass
void fluid_wrench(const Model& model, int b, const Transform& body_frame, const Vec3& v, const Vec3& w,
                  Scalar wrench[6]);

// the wrenches body_f ([force at the centre of mass; torque] per body) with what the model applies added, into out
// (its storage kept from call to call): the compensation, the fluid's, the spatial tendons' springs' and dampers', and
// the site and spatial tendon actuators' at the control's commands (none where control is null: inverse dynamics
// leaves actuators out), with the bodies where the state's joint_q and joint_qd put them
void applied_wrenches(const Model& model, ModelWrenches& wrenches, const State& state, const Control* control,
                      std::vector<Scalar>& out);

}  // namespace novaphy
