#include "engine/solver/solver_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>

#include "engine/collision/shape_filter.h"
#include "engine/model/spatial_tendon.h"
#include "engine/threads/parallel.h"
#include "kernels/crba.h"
#include "kernels/fk.h"

namespace novaphy {

namespace {

// the distinct values of P (by their bits) in a table, each value's index in it: a model of replicated robots
// has few distinct actuators or shapes
template <typename P>
class Distinct {
 public:
  int index(const P& p, std::vector<P>& table) {
    std::array<unsigned char, sizeof(P)> bits;
    std::memcpy(bits.data(), &p, sizeof(P));
    const auto [it, added] = index_.try_emplace(bits, static_cast<int>(table.size()));
    if (added) table.push_back(p);
    return it->second;
  }

 private:
  std::map<std::array<unsigned char, sizeof(P)>, int> index_;
};

}  // namespace

SolverModel::SolverModel(const Model& model, bool weld) : welded(weld_fixed_joints(model, weld)) {
  index_articulations(model);
  group_actuators(model);
  index_inputs(model);
  index_contacts(model);
  index_limits(model);
  mark_constrained(model);
  weigh_energy(model);
}

void SolverModel::read_parameters(const Model& model, const std::vector<std::uint8_t>& worlds, int threads) {
  if (!welded.welded_bodies.empty()) {
    welded.model.copy_parameters(model);
    weld_masses(model, welded, worlds);
  }
  // from the first change on, one entry per actuator and shape (randomised worlds share none): every one made once
  const bool shared = actuator_params.size() != dof_actuators.size();
  if (shared) {
    actuator_params.resize(dof_actuators.size());
    for (size_t k = 0; k < dof_actuators.size(); ++k) {
      dof_actuators[k].params = static_cast<int>(k);
      actuator_params[k] = novaphy::actuator_params(model, dof_actuators[k].u);
    }
  }
  // (a visual shape's material is never read: it has no contacts)
  const bool shared_materials = contact_materials.size() != shape_material.size();
  if (shared_materials) {
    contact_materials.assign(shape_material.size(), ContactMaterial{});
    for (int s = 0; s < model.shape_count; ++s) {
      shape_material[s] = s;
      if (!shape_visual_only(model, s)) contact_materials[s] = contact_material(model, s);
    }
  }
  if (!shared)
    parallel_for(std::clamp(threads, 1, std::max(model.joint_dof_count, 1)), model.joint_dof_count, [&](int d) {
      if (worlds[model.articulation_world(index.dof_articulation[d])])
        for (int k = dof_actuator_start[d]; k < dof_actuator_start[d + 1]; ++k)
          actuator_params[k] = novaphy::actuator_params(model, dof_actuators[k].u);
    });
  if (!shared_materials)
    parallel_for(std::clamp(threads, 1, std::max(model.shape_count, 1)), model.shape_count, [&](int s) {
      const int w = model.shape_world[s];
      if (w < 0 || !worlds[w] || shape_visual_only(model, s)) return;
      // the material's numbers set_parameter writes (engine/model/parameters.cpp); the rest are the model's structure
      ContactMaterial& m = contact_materials[s];
      m.mu = model.shape_mu[s];
      m.torsion = model.shape_mu_torsion[s];
      m.rolling = model.shape_mu_rolling[s];
      m.priority = model.shape_priority[s];
    });
}

void SolverModel::index_articulations(const Model& model) {
  const Model& kernel_model = welded.welded_bodies.empty() ? model : welded.model;
  for (int a = 0; a < model.articulation_count; ++a) art.push_back(kernel_model.articulation(a));
  index.body_articulation.assign(model.body_count, -1);
  index.body_link.assign(model.body_count, -1);
  for (int j = 0; j < kernel_model.joint_count; ++j) {
    const int a = kernel_model.joint_articulation[j];
    index.body_articulation[kernel_model.joint_child[j]] = a;
    index.body_link[kernel_model.joint_child[j]] = j - kernel_model.articulation_start[a];
  }
  welded_into.resize(model.articulation_count);
  for (const int b : welded.welded_bodies) {
    const int link_body = welded.link_body[b];
    index.body_articulation[b] = index.body_articulation[link_body];
    index.body_link[b] = index.body_link[link_body];
    welded_into[index.body_articulation[b]].push_back({b, index.body_link[b], welded.offset[b]});
  }
  index.dof_articulation.resize(model.joint_dof_count);
  for (int a = 0; a < model.articulation_count; ++a) {
    index.dof_count.push_back(art[a].dof_count());
    std::fill_n(index.dof_articulation.begin() + art[a].qd_begin(), art[a].dof_count(), a);
  }
}

void SolverModel::group_actuators(const Model& model) {
  std::vector<int> by_dof(model.actuator_count);
  dof_actuator_start.resize(model.joint_dof_count + 1);
  std::vector<int> next(std::max(model.joint_dof_count, model.tendon_count) + 1);
  group_by_key(
      model.actuator_count, model.joint_dof_count,
      [&](int u) { return model.actuator_joint[u] < 0 ? -1 : model.joint_qd_start[model.actuator_joint[u]]; },
      dof_actuator_start.data(), by_dof.data(), next.data());
  Distinct<ActuatorParams> distinct;
  for (int k = 0; k < dof_actuator_start[model.joint_dof_count]; ++k) {
    const int u = by_dof[k];
    const int params = distinct.index(novaphy::actuator_params(model, u), actuator_params);
    dof_actuators.push_back({u, model.joint_q_start[model.actuator_joint[u]], params});
  }
  tendon_actuators.resize(model.actuator_count);
  tendon_actuator_start.resize(model.tendon_count + 1);
  group_by_key(
      model.actuator_count, model.tendon_count, [&](int u) { return model.actuator_tendon[u]; },
      tendon_actuator_start.data(), tendon_actuators.data(), next.data());
  dof_entries.resize(model.tendon_entry_count);
  dof_entry_start.resize(model.joint_dof_count + 1);
  group_by_key(
      model.tendon_entry_count, model.joint_dof_count, [&](int e) { return model.tendon_dof[e]; },
      dof_entry_start.data(), dof_entries.data(), next.data());
  for (int t = 0; t < model.tendon_count; ++t)
    entry_tendon.insert(entry_tendon.end(), model.tendon_start[t + 1] - model.tendon_start[t], t);
}

void SolverModel::index_inputs(const Model& model) {
  const int articulations = model.articulation_count;
  std::vector<int> next(articulations + 1);
  auto group = [&](int count, auto&& key, std::vector<int>& start, std::vector<int>& items, std::vector<int>& loose) {
    start.assign(articulations + 1, 0);
    items.assign(count, -1);
    group_by_key(count, articulations, key, start.data(), items.data(), next.data());
    items.resize(start[articulations]);
    for (int i = 0; i < count; ++i)
      if (key(i) < 0) loose.push_back(i);
  };
  group(
      model.body_count, [&](int b) { return index.body_articulation[b]; }, art_body_start, art_body_runs, loose_bodies);
  group(
      model.actuator_count,
      [&](int u) {
        const int joint = model.actuator_joint[u], tendon = model.actuator_tendon[u], body = model.actuator_body[u];
        if (joint >= 0) return index.dof_articulation[model.joint_qd_start[joint]];
        if (body >= 0) return index.body_articulation[body];
        return tendon >= 0 ? tendon_home(model, tendon) : -1;
      },
      art_actuator_start, art_actuator_runs, loose_actuators);
  // the bodies and actuators as runs of consecutive indices (a robot's are one run each): [begin, count] pairs
  auto to_runs = [&](std::vector<int>& start, std::vector<int>& items) {
    std::vector<int> runs, run_start(articulations + 1, 0);
    for (int a = 0; a < articulations; ++a) {
      for (int k = start[a]; k < start[a + 1]; ++k) {
        if (k > start[a] && items[k] == items[k - 1] + 1) {
          ++runs.back();
          continue;
        }
        runs.push_back(items[k]);
        runs.push_back(1);
      }
      run_start[a + 1] = static_cast<int>(runs.size()) / 2;
    }
    start = std::move(run_start);
    items = std::move(runs);
  };
  to_runs(art_body_start, art_body_runs);
  to_runs(art_actuator_start, art_actuator_runs);
  // the fixed tendons (a tendon's dofs are one articulation's: the builder's rule; a spatial tendon's forces are
  // wrenches on its bodies)
  std::vector<int> spatial;
  group(
      model.tendon_count, [&](int t) { return is_spatial(model, t) ? -1 : tendon_home(model, t); }, art_tendon_start,
      art_tendons, spatial);
}

int SolverModel::tendon_home(const Model& model, int t) const {
  if (!is_spatial(model, t)) return index.dof_articulation[model.tendon_dof[model.tendon_start[t]]];
  for (int e = model.tendon_path_start[t]; e < model.tendon_path_start[t + 1]; ++e)
    if (index.moving(model.tendon_path_body[e]) >= 0) return index.moving(model.tendon_path_body[e]);
  return -1;
}

void SolverModel::index_contacts(const Model& model) {
  Distinct<ContactMaterial> materials;
  for (int s = 0; s < model.shape_count; ++s) {
    contact_dims = std::max(contact_dims, ContactRows::count(model.shape_condim[s]));
    shape_material.push_back(materials.index(contact_material(model, s), contact_materials));
    shape_weight.push_back(contact_weight(model, s));
  }
}

void SolverModel::index_limits(const Model& model) {
  for (int j = 0; j < model.joint_count; ++j) {
    const auto type = static_cast<JointType>(model.joint_type[j]);
    const int dof = model.joint_qd_start[j];
    if ((type == JointType::Revolute || type == JointType::Prismatic) &&
        (std::isfinite(model.joint_limit_lower[dof]) || std::isfinite(model.joint_limit_upper[dof])))
      limited_joints.push_back(j);
  }
  std::stable_sort(limited_joints.begin(), limited_joints.end(),
                   [&](int x, int y) { return model.joint_articulation[x] < model.joint_articulation[y]; });
  limited_start.assign(model.articulation_count + 1, 0);
  for (const int j : limited_joints) ++limited_start[model.joint_articulation[j] + 1];
  for (int a = 0; a < model.articulation_count; ++a) limited_start[a + 1] += limited_start[a];
  limit_slot.assign(model.joint_dof_count, -1);
  for (size_t m = 0; m < limited_joints.size(); ++m)
    limit_slot[model.joint_qd_start[limited_joints[m]]] = static_cast<int>(m);
}

void SolverModel::mark_constrained(const Model& model) {
  constrained.assign(model.articulation_count, 0);
  equality_articulation.assign(model.equality_count, -1);
  tendon_articulation.assign(model.tendon_count, -1);
  for (int e = 0; e < model.equality_count; ++e) {
    const int* object = &model.equality_object[2 * e];
    for (int k = 0; k < 2; ++k) {
      int a = -1;
      if (static_cast<EqualityType>(model.equality_type[e]) != EqualityType::JointCoupling)
        a = index.moving(object[k]);
      else if (object[k] >= 0)
        a = index.dof_articulation[model.joint_qd_start[object[k]]];
      if (a < 0) continue;
      constrained[a] = 1;
      if (equality_articulation[e] < 0) equality_articulation[e] = a;
    }
  }
  for (int t = 0; t < model.tendon_count; ++t) {
    tendon_articulation[t] = tendon_home(model, t);
    if (!std::isfinite(model.tendon_limit_lower[t]) && !std::isfinite(model.tendon_limit_upper[t]) &&
        !(model.tendon_frictionloss[t] > 0))
      continue;
    if (!is_spatial(model, t)) constrained[tendon_articulation[t]] = 1;
    for (int e = model.tendon_path_start[t]; e < model.tendon_path_start[t + 1]; ++e) {
      const int a = index.moving(model.tendon_path_body[e]);
      if (a >= 0) constrained[a] = 1;
    }
  }
}

void SolverModel::weigh_energy(const Model& model) {
  energy_weight.assign(model.joint_dof_count, 0);
  std::vector<Scalar> mass(model.articulation_count, 0);
  for (int b = 0; b < model.body_count; ++b)
    if (index.body_articulation[b] >= 0) mass[index.body_articulation[b]] += model.body_mass[b];
  ArticulationScratch s;
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView& view = art[a];
    if (view.dof_count() == 0 || !(mass[a] > 0)) continue;
    s.resize(view);
    forward_kinematics(view, model.joint_q0.data() + view.q_begin(), s);
    crba(view, s);
    for (int k = 0; k < view.dof_count(); ++k) energy_weight[view.qd_begin() + k] = s.H(k, k) / mass[a];
  }
}

}  // namespace novaphy
