// What SolverFeatherstone builds once for a model (as MuJoCo's mjModel beside mjData): the articulations the
// kernels see, where bodies and dofs sit among them, the limited joints, the actuator, tendon and contact tables,
// each articulation's runs of inputs and the guard's energy weights. Read-only once made; what a step writes is
// SolverData (engine/solver/solver_data.h), what it reads of the settings StepContext (engine/solver/route.h).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "engine/model/actuator.h"
#include "engine/model/group_by_key.h"
#include "engine/model/weld.h"
#include "engine/solver/blocks/blocks.h"
#include "engine/solver/parts/rows.h"
#include "engine/solver/route.h"

namespace novaphy {

struct SolverModel {
  // `weld`: bodies held by Fixed joints merged into their parent's link (settings.weld_fixed_joints)
  SolverModel(const Model& model, bool weld);
  // what depends on the parameters Model::set_parameter writes, read again for the worlds w with worlds[w] != 0:
  // the welded links' masses, the actuators' and shapes' numbers (from the first change on, each actuator and
  // shape has its own entry in actuator_params and contact_materials: randomised worlds share none)
  // (on `threads` threads)
  void read_parameters(const Model& model, const std::vector<std::uint8_t>& worlds, int threads);

  WeldedModel welded;  // what the kernels see: art views its arrays
  std::vector<ArticulationView> art;
  std::vector<std::vector<WeldedBody>> welded_into;  // per articulation: its welded bodies
  ArticulationIndex index;
  // Revolute and Prismatic joints with a finite limit, by articulation (a's from limited_start[a]), and per dof
  // its joint's place among them (-1: none)
  std::vector<int> limited_joints, limited_start, limit_slot;
  // per dof: the actuators that drive it, in order, dof_actuators[dof_actuator_start[d] .. [d + 1]): each one's
  // index, its joint's coordinate and its numbers in actuator_params, the distinct ones of the Model (read-only
  // after finalize): replicated robots' actuators share them, so a step reads one small table
  struct DofActuator {
    int u, q, params;
  };
  std::vector<int> dof_actuator_start;
  std::vector<DofActuator> dof_actuators;
  std::vector<ActuatorParams> actuator_params;
  // per tendon: the actuators on it, tendon_actuators[tendon_actuator_start[t] .. [t + 1]); per dof: the tendon
  // entries on it likewise (dof_entries, dof_entry_start), entry_tendon: each entry's tendon
  std::vector<int> tendon_actuator_start, tendon_actuators, dof_entry_start, dof_entries, entry_tendon;
  // per shape: its contact numbers' place in contact_materials, the distinct ones, and its body's invweight0
  std::vector<int> shape_material;
  std::vector<Scalar> shape_weight;
  std::vector<ContactMaterial> contact_materials;
  int contact_dims = 3;  // the rows of a contact of the most, by the shapes' condim (ContactLists::dims)
  // per articulation: 1 where an equality constraint, a tendon limit or a tendon's dry friction acts on it (its rows
  // are always the islands')
  std::vector<std::uint8_t> constrained;
  // per equality and tendon the articulation whose world it is in (the first it acts on that moves, -1: none)
  std::vector<int> equality_articulation, tendon_articulation;
  // tendon t's articulation: its dofs' (fixed), its path's first moving body's (spatial; -1: none moves)
  int tendon_home(const Model& model, int t) const;
  std::vector<Scalar> energy_weight;  // [dof] the guard's (engine/solver/parts/guard.h)
  // per articulation its bodies and actuators as runs ([begin, count] pairs from *_start[a]) and its tendons; the
  // bodies and actuators of none
  std::vector<int> art_body_start, art_body_runs, art_actuator_start, art_actuator_runs;
  std::vector<int> art_tendon_start, art_tendons;
  std::vector<int> loose_bodies, loose_actuators;

 private:
  void index_articulations(const Model& model);
  // the actuators by dof and by tendon, the tendon entries by dof
  void group_actuators(const Model& model);
  // per articulation what its step reads beside its coordinates and dofs: its bodies (body_f), actuators, tendons
  void index_inputs(const Model& model);
  void index_limits(const Model& model);
  void index_contacts(const Model& model);
  void mark_constrained(const Model& model);
  // per dof H_kk at joint_q0 over its articulation's mass (its links' and welded bodies')
  void weigh_energy(const Model& model);
};

}  // namespace novaphy
