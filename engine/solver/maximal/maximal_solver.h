// What the solvers in maximal coordinates share (SolverSemiImplicit, SolverXPBD): the step's frame around their own
// per-world stepping of bodies. A step checks its arguments, lists the contacts by world, steps every world (worlds
// spread over threads, each world's arithmetic in one fixed order: the same bits on any thread count), runs the
// divergence guard per world, and writes the output: body_q and body_qd, joint_q and joint_qd from the bodies
// (MaximalConstraints::joint_coordinates), rounded to float for a Float32 model.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/solver/joint_support.h"
#include "engine/solver/maximal/constraints.h"
#include "engine/solver/parts/contact_material.h"
#include "engine/solver/settings.h"
#include "engine/threads/exclusive_call.h"

namespace novaphy {

// the forces along one axis of a constraint with a dof (model.h: a joint's spring, damper, PD drive, actuators and
// joint_f): pull + force - stiffness x - damping x_dot, with x the axis's coordinate, taken implicitly. pull is what
// the stiffnesses pull towards (sum K_i x_i: a drive's ke target_pos, a spring's stiffness q_ref, a servo's kp ctrl),
// force the rest (joint_f, a drive's kd target_vel, a motor's force)
struct AxisSpring {
  Scalar pull = 0, force = 0;
  Scalar stiffness = 0;  // K
  Scalar damping = 0;    // D
  bool any() const { return pull != 0 || force != 0 || stiffness != 0 || damping != 0; }
  // where the stiffness alone would hold the axis (K > 0)
  Scalar rest() const { return pull / stiffness; }
};

// what the divergence guard reads of a solver's settings
struct GuardSettings {
  DivergencePolicy on_divergence = DivergencePolicy::Flag;
  Scalar speed = 0, depth = 0;
};

class MaximalSolver {
 public:
  MaximalSolver(const MaximalSolver&) = delete;
  MaximalSolver& operator=(const MaximalSolver&) = delete;
  virtual ~MaximalSolver() = default;

  // state_in may be state_out; on error nothing is written but contact_impulse. One step at a time: a step called
  // while another thread's step of this solver runs throws Error (one solver per thread)
  void step(const State& state_in, State& state_out, const Control& control, Contacts& contacts, Scalar dt);
  // holds this solver's one-call flag for the caller's scope (the binding's float32 conversions)
  ExclusiveCall hold() { return ExclusiveCall(busy_, step_name_.c_str()); }
  JointSupportMatrix joint_support() const { return novaphy::joint_support(name_, true); }
  // per world: 1 where the last step's divergence guard fired
  const std::vector<std::uint8_t>& diverged() const { return diverged_; }
  const Model& model() const { return model_; }
  // what of the model the solver does not model, by name (a joint's armature and dry friction): the binding warns
  const std::vector<std::string>& ignored() const { return ignored_; }

 protected:
  MaximalSolver(const Model& model, const char* name);

  // what step_world reads
  struct StepInput {
    const State& in;
    const Control& control;
    Contacts& contacts;
    Scalar dt;
  };
  // world w's moving bodies stepped into next_ (their slots: body_slot_), its contacts' impulses into contacts
  virtual void step_world(int w, const StepInput& step, int thread) = 0;
  virtual void check_settings() const = 0;
  virtual int thread_count() const = 0;
  virtual GuardSettings guard_settings() const = 0;

  // world w's bodies (their slots' motions) sped up by the forces over dt: gravity (less its compensation), body_f,
  // the fluid's, the gyroscopic torque, the actuators on sites, and joint_f of Free and Ball joints (a scalar dof's is
  // its axis's AxisSpring force)
  void forces(int w, const State& in, const Control& control, Scalar dt, std::vector<BodyMotion>& bodies) const;
  // body b's place among its world's bodies (-1: the world)
  int slot(int b) const { return b >= 0 ? body_slot_[b] : -1; }
  // body b's motion at the step's start (a static body's: at rest, no mass)
  BodyMotion start_motion(const State& in, int b) const;
  // the spring along constraint c's axis k (its dof's; none without one), at the axis's coordinate x (a Revolute or
  // Prismatic joint's joint_q, which winds on) and velocity x_dot
  AxisSpring axis_spring(const MaximalConstraint& c, int k, const State& in, const Control& control) const;
  // the coordinate a constraint's axis k is driven and limited at: its joint's joint_q for a Revolute or Prismatic
  // joint, else `coordinate` (constraint_coordinates')
  Scalar axis_coordinate(const MaximalConstraint& c, int k, const State& in, Scalar coordinate) const;
  // this step's contacts of world w: world_contacts_[contact_start_[w] ..)
  const int* contacts_of(int w, int* count) const {
    *count = contact_start_[w + 1] - contact_start_[w];
    return world_contacts_.data() + contact_start_[w];
  }

  const Model& model_;
  const char* name_;
  std::string step_name_;  // "<name>.step"

  MaximalConstraints built_;
  std::vector<int> body_slot_;    // each body's place among its world's (world_bodies from body_start)
  std::vector<BodyMotion> next_;  // per body: its motion after the step
  ShapeContacts shapes_;          // the shapes' contact numbers (read again where set_parameter wrote them)
  int threads_ = 1;               // the threads the scratch is kept for

 private:
  void check_step(const State& in, const State& out, const Control& control, const Contacts& contacts, Scalar dt);
  // the shapes' contact numbers and the bodies' masses and inertias (a stand-in's, MaximalConstraints), as the
  // model's per-world parameters are now
  void read_materials();
  void read_masses();
  void list_contacts(const Contacts& contacts);
  bool world_diverged(int w, const Contacts& contacts, const GuardSettings& guard) const;
  void write_world(int w, const State& in, State& out) const;

  std::vector<Scalar> inv_mass_;                       // per body (0: static)
  std::vector<Mat3> inertia_body_, inv_inertia_body_;  // per body, about its COM in its frame
  std::vector<ContactMaterial> materials_;
  std::vector<int> shape_material_;
  std::vector<Scalar> shape_weight_;
  std::uint64_t parameters_read_ = 0;
  std::vector<int> dof_actuator_start_, dof_actuators_;             // the actuators of each dof
  std::vector<int> site_actuator_start_, site_actuators_;           // the actuators on sites of each world
  std::vector<int> contact_start_, world_contacts_, contact_next_;  // this step's contacts by world (group_by_key)
  std::vector<std::uint8_t> diverged_;
  std::vector<std::string> ignored_;
  CallFlag busy_;
};

}  // namespace novaphy
