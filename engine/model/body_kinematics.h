// The bodies' state from their articulations' links, and the inverse weights finalize() derives from them, on the
// kernels (kernels/fk, kernels/osim): in the model's room, below the whole-model evaluations (engine/eval/) and the
// solver, which use it too.
#pragma once

#include "engine/model/model.h"
#include "kernels/articulation.h"

namespace novaphy {

// body_q / body_qd of body b, riding on link `link` at `offset` (its pose in the link frame) with its
// centre of mass at `com` (body frame), from scratch after forward_kinematics + forward_velocity
void store_body(const ArticulationScratch& s, int link, const Transform& offset, const Vec3& com, int b, State& state);
// store_body for every link body of the articulation
void store_body_state(const ArticulationView& art, const ArticulationScratch& s, State& state);

// FK and link velocities of articulation a at the state's coordinates, into s
ArticulationView kinematics(const Model& model, const State& state, int a, ArticulationScratch& s);

// state.body_q and state.body_qd from state.joint_q and state.joint_qd, unchecked (eval_fk checks them first)
void bodies_from_joints(const Model& model, State& state);

// model.body_invweight0, and joint_invweight0 and tendon_invweight0 when some soft row needs them (model.h), MuJoCo's,
// from joint_q0: the builder's last step
void set_invweight0(Model& model);

}  // namespace novaphy
