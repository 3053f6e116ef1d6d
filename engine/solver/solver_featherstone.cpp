#include "engine/solver/solver_featherstone.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <type_traits>

#include "engine/model/actuator.h"
#include "engine/model/error.h"
#include "engine/solver/parts/rows.h"
#include "engine/threads/parallel.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/stream.h"

namespace novaphy {

namespace {

// items [0, n) grouped by key (in [0, buckets); a negative key leaves the item out), a counting sort:
// items[start[k] .. start[k + 1]) are key k's, ascending; `next` is scratch of buckets + 1
template <typename Key>
void group_by_key(int n, int buckets, Key key, int* start, int* items, int* next) {
  std::fill_n(start, buckets + 1, 0);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) ++start[key(i) + 1];
  for (int k = 0; k < buckets; ++k) start[k + 1] += start[k];
  std::copy_n(start, buckets, next);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) items[next[key(i)]++] = i;
}

// no thread wakes in the contact lists for fewer contacts (a parallel region costs about as much)
constexpr int kContactsPerThread = 512;

}  // namespace

void SolverData::allocate(const SolverCounts& n) {
#define NOVAPHY_ALLOCATE_DATA(type, name, count, doc) \
  if (name.size() < static_cast<size_t>(count)) name.resize(static_cast<size_t>(count), type{});
  NOVAPHY_SOLVER_DATA(NOVAPHY_ALLOCATE_DATA)
#undef NOVAPHY_ALLOCATE_DATA
}

std::size_t SolverData::bytes() const {
  std::size_t n = 0;
#define NOVAPHY_DATA_BYTES(type, name, count, doc) n += name.size() * sizeof(type);
  NOVAPHY_SOLVER_DATA(NOVAPHY_DATA_BYTES)
#undef NOVAPHY_DATA_BYTES
  return n;
}

bool JointSupportMatrix::supports(const std::string& joint) const {
  for (const Entry& e : entries)
    if (e.joint == joint) return e.supported;
  fail("unknown joint type '", joint, "'");
}

std::string JointSupportMatrix::to_string() const {
  std::ostringstream os;
  os << "SolverFeatherstone joint support:";
  for (const Entry& e : entries) os << "\n  " << e.joint << ": " << (e.supported ? "yes" : "no");
  return os.str();
}

JointSupportMatrix SolverFeatherstone::joint_support() const {
  return {{{"Revolute", true},
           {"Prismatic", true},
           {"Slide", true},
           {"Ball", true},
           {"Fixed", true},
           {"Free", true},
           {"Distance", false},
           {"D6", false},
           {"Cable", false}}};
}

// ---- made once: the articulations the kernels see, where bodies and dofs sit, the routes and their data

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

SolverFeatherstone::SolverFeatherstone(const Model& model, const SolverFeatherstoneSettings& settings_)
    : settings(settings_), model_(model), welded_(weld_fixed_joints(model, settings_.weld_fixed_joints)) {
  settings.check();
  max_threads_ = std::max(1, omp_get_max_threads());
  if (model.articulation_count == 0) fail("SolverFeatherstone needs a model with at least one articulation");
  const Model& kernel_model = welded_.welded_bodies.empty() ? model : welded_.model;
  for (int a = 0; a < model.articulation_count; ++a) art_.push_back(kernel_model.articulation(a));
  index_.body_articulation.assign(model.body_count, -1);
  index_.body_link.assign(model.body_count, -1);
  for (int j = 0; j < kernel_model.joint_count; ++j) {
    const int a = kernel_model.joint_articulation[j];
    index_.body_articulation[kernel_model.joint_child[j]] = a;
    index_.body_link[kernel_model.joint_child[j]] = j - kernel_model.articulation_start[a];
  }
  welded_into_.resize(model.articulation_count);
  for (const int b : welded_.welded_bodies) {
    const int link_body = welded_.link_body[b];
    index_.body_articulation[b] = index_.body_articulation[link_body];
    index_.body_link[b] = index_.body_link[link_body];
    welded_into_[index_.body_articulation[b]].push_back({b, index_.body_link[b], welded_.offset[b]});
  }
  index_.dof_articulation.resize(model.joint_dof_count);
  for (int a = 0; a < model.articulation_count; ++a) {
    index_.dof_count.push_back(art_[a].dof_count());
    std::fill_n(index_.dof_articulation.begin() + art_[a].qd_begin(), art_[a].dof_count(), a);
  }
  group_actuators();
  index_inputs();
  Distinct<ContactMaterial> materials;
  for (int s = 0; s < model.shape_count; ++s) {
    contact_dims_ = std::max(contact_dims_, contact_row_count(model.shape_condim[s]));
    shape_material_.push_back(materials.index(contact_material(model, s), contact_materials_));
    shape_weight_.push_back(contact_weight(model, s));
  }
  shape_contacts_ = {contact_materials_.data(),
                     shape_material_.data(),
                     shape_weight_.data(),
                     nullptr,
                     static_cast<int>(contact_materials_.size()),
                     model.friction_rule,
                     0};

  // limits kept per limited joint, by articulation: the blocks lay out their articulations' cells, the
  // others follow
  for (int j = 0; j < model.joint_count; ++j) {
    const auto type = static_cast<JointType>(model.joint_type[j]);
    const int dof = model.joint_qd_start[j];
    if ((type == JointType::Revolute || type == JointType::Prismatic) &&
        (std::isfinite(model.joint_limit_lower[dof]) || std::isfinite(model.joint_limit_upper[dof])))
      limited_joints_.push_back(j);
  }
  std::stable_sort(limited_joints_.begin(), limited_joints_.end(),
                   [&](int x, int y) { return model.joint_articulation[x] < model.joint_articulation[y]; });
  limited_start_.assign(model.articulation_count + 1, 0);
  for (const int j : limited_joints_) ++limited_start_[model.joint_articulation[j] + 1];
  for (int a = 0; a < model.articulation_count; ++a) limited_start_[a + 1] += limited_start_[a];
  std::vector<int> limit_slot(model.joint_dof_count, -1);
  for (size_t m = 0; m < limited_joints_.size(); ++m)
    limit_slot[model.joint_qd_start[limited_joints_[m]]] = static_cast<int>(m);

  std::vector<std::uint8_t> batchable(model.articulation_count, 0);
  for (int a = 0; a < model.articulation_count; ++a) batchable[a] = art_[a].dof_count() > 0;
  if (std::find(batchable.begin(), batchable.end(), 1) != batchable.end())
    batches_ = ArticulationBatches::make(kernel_model, art_, batchable, welded_into_, model.body_com, limit_slot,
                                         model.precision);
  limit_cell_.assign(2 * limited_joints_.size(), -1);
  int cells = 0;
  if (batches_) {
    const std::vector<int>& batched = batches_->limit_cells();
    std::copy(batched.begin(), batched.end(), limit_cell_.begin());
    cells = batches_->limit_cell_count();
  }
  for (int& cell : limit_cell_)
    if (cell < 0) cell = cells++;
  dense_ = std::make_unique<DenseArticulations>(model, art_, welded_into_);
  islands_ = std::make_unique<IslandRows>(model, art_, index_, limited_joints_, limited_start_, limit_cell_);
  route_.assign(model.articulation_count, nullptr);
  counts_ = {model.joint_dof_count, model.joint_coord_count, model.articulation_count, cells, 0,
             model.tendon_count,    model.equality_count};
  data_.allocate(counts_);
  std::fill(data_.factor_failure.begin(), data_.factor_failure.end(), -1);
  reset_q_ = model.joint_q0;
  reset_qd_.assign(model.joint_dof_count, 0);
  weigh_energy();
  mark_constrained();
  step_bytes_ = static_cast<std::int64_t>(memory_bytes()) +
                static_cast<std::int64_t>(sizeof(Scalar)) * (model.joint_coord_count + model.joint_dof_count +
                                                             (7 + 6 + 6) * static_cast<std::int64_t>(model.body_count));
}

void SolverFeatherstone::weigh_energy() {
  // per dof H_kk at joint_q0 over its articulation's mass (its links' and welded bodies')
  energy_weight_.assign(model_.joint_dof_count, 0);
  std::vector<Scalar> mass(model_.articulation_count, 0);
  for (int b = 0; b < model_.body_count; ++b)
    if (index_.body_articulation[b] >= 0) mass[index_.body_articulation[b]] += model_.body_mass[b];
  ArticulationScratch s;
  for (int a = 0; a < model_.articulation_count; ++a) {
    const ArticulationView& art = art_[a];
    if (art.dof_count() == 0 || !(mass[a] > 0)) continue;
    s.resize(art);
    forward_kinematics(art, model_.joint_q0.data() + art.q_begin(), s);
    crba(art, s);
    for (int k = 0; k < art.dof_count(); ++k) energy_weight_[art.qd_begin() + k] = s.H(k, k) / mass[a];
  }
}

void SolverFeatherstone::set_reset_state(const State& state) {
  model_.check(state);
  for (const std::vector<Scalar>* x : {&state.joint_q, &state.joint_qd})
    for (size_t k = 0; k < x->size(); ++k)
      if (!std::isfinite((*x)[k]))
        fail("reset state: ", x == &state.joint_q ? "joint_q" : "joint_qd", "[", k, "] is not finite: ", (*x)[k]);
  reset_q_ = state.joint_q;
  reset_qd_ = state.joint_qd;
}

void SolverFeatherstone::group_actuators() {
  std::vector<int> by_dof(model_.actuator_count);
  dof_actuator_start_.resize(model_.joint_dof_count + 1);
  std::vector<int> next(std::max(model_.joint_dof_count, model_.tendon_count) + 1);
  group_by_key(
      model_.actuator_count, model_.joint_dof_count,
      [&](int u) { return model_.actuator_joint[u] < 0 ? -1 : model_.joint_qd_start[model_.actuator_joint[u]]; },
      dof_actuator_start_.data(), by_dof.data(), next.data());
  Distinct<ActuatorParams> distinct;
  dof_actuators_.clear();
  for (int k = 0; k < dof_actuator_start_[model_.joint_dof_count]; ++k) {
    const int u = by_dof[k];
    const int params = distinct.index(actuator_params(model_, u), actuator_params_);
    dof_actuators_.push_back({u, model_.joint_q_start[model_.actuator_joint[u]], params});
  }
  tendon_actuators_.resize(model_.actuator_count);
  tendon_actuator_start_.resize(model_.tendon_count + 1);
  group_by_key(
      model_.actuator_count, model_.tendon_count, [&](int u) { return model_.actuator_tendon[u]; },
      tendon_actuator_start_.data(), tendon_actuators_.data(), next.data());
  dof_entries_.resize(model_.tendon_entry_count);
  dof_entry_start_.resize(model_.joint_dof_count + 1);
  group_by_key(
      model_.tendon_entry_count, model_.joint_dof_count, [&](int e) { return model_.tendon_dof[e]; },
      dof_entry_start_.data(), dof_entries_.data(), next.data());
  for (int t = 0; t < model_.tendon_count; ++t)
    entry_tendon_.insert(entry_tendon_.end(), model_.tendon_start[t + 1] - model_.tendon_start[t], t);
}

void SolverFeatherstone::index_inputs() {
  const int articulations = model_.articulation_count;
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
      model_.body_count, [&](int b) { return index_.body_articulation[b]; }, art_body_start_, art_body_runs_,
      loose_bodies_);
  group(
      model_.actuator_count,
      [&](int u) {
        const int joint = model_.actuator_joint[u], tendon = model_.actuator_tendon[u];
        if (joint >= 0) return index_.dof_articulation[model_.joint_qd_start[joint]];
        return tendon >= 0 ? index_.dof_articulation[model_.tendon_dof[model_.tendon_start[tendon]]] : -1;
      },
      art_actuator_start_, art_actuator_runs_, loose_actuators_);
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
  to_runs(art_body_start_, art_body_runs_);
  to_runs(art_actuator_start_, art_actuator_runs_);
  // (a tendon's dofs are one articulation's: the builder's rule)
  std::vector<int> none;
  group(
      model_.tendon_count, [&](int t) { return index_.dof_articulation[model_.tendon_dof[model_.tendon_start[t]]]; },
      art_tendon_start_, art_tendons_, none);
}

void SolverFeatherstone::mark_constrained() {
  constrained_.assign(model_.articulation_count, 0);
  auto mark_body = [&](int body) {
    if (index_.moving(body) >= 0) constrained_[index_.moving(body)] = 1;
  };
  auto mark_dof = [&](int dof) { constrained_[index_.dof_articulation[dof]] = 1; };
  for (int e = 0; e < model_.equality_count; ++e) {
    const int* object = &model_.equality_object[2 * e];
    for (int k = 0; k < 2; ++k) {
      if (static_cast<EqualityType>(model_.equality_type[e]) != EqualityType::JointCoupling)
        mark_body(object[k]);
      else if (object[k] >= 0)
        mark_dof(model_.joint_qd_start[object[k]]);
    }
  }
  for (int t = 0; t < model_.tendon_count; ++t)
    if (std::isfinite(model_.tendon_limit_lower[t]) || std::isfinite(model_.tendon_limit_upper[t]))
      mark_dof(model_.tendon_dof[model_.tendon_start[t]]);
  std::copy(constrained_.begin(), constrained_.end(), data_.touched.begin());
}

std::size_t SolverFeatherstone::memory_bytes() const {
  std::size_t n = (batches_ ? batches_->bytes() : 0) + dense_->bytes() + islands_->bytes() + data_.bytes();
  return n + (limit_cell_.size() + limited_joints_.size()) * sizeof(int);
}

int SolverFeatherstone::thread_count() const {
  // no more than the threads the routes keep scratch for (OpenMP's count when the solver was made)
  return std::clamp(settings.num_threads > 0 ? settings.num_threads : omp_get_max_threads(), 1, max_threads_);
}

// ---- the step

void SolverFeatherstone::step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt) {
  const ExclusiveCall exclusive(busy_, "SolverFeatherstone.step");
  const std::int64_t start = settings.count_serial_time ? now_ns() : 0;
  check_step(in, out, control, contacts, dt);
  plan();
  StepContext step = begin_step(in, out, control, contacts, dt);
  actuate(control, step);
  list_contacts(contacts, step);
  const Stage last = settings.on_divergence == DivergencePolicy::Raise ? Stage::Integrate : Stage::Store;
  if (step.split) {
    pass(step, Stage::Dynamics, Stage::Rows);
    solve_islands(step);
    pass(step, Stage::Integrate, last);
  } else {
    pass(step, Stage::Dynamics, last);
  }
  guard(step);
  if (last != Stage::Store) pass(step, Stage::Store, Stage::Store);
  end_step(in, out, step);
  if (!settings.count_serial_time) return;
  serial_seconds_.step += 1e-9 * static_cast<double>(now_ns() - start);
  ++serial_seconds_.steps;
}

void SolverFeatherstone::plan() {
  // the blocks step the batches of fewer than aba_min_dofs dofs, unless the settings ask for the dense route
  const bool blocks = batches_ && settings.use_batch_kernels && settings.coriolis_implicitness == 0;
  const int max_dofs = blocks ? settings.aba_min_dofs : 0;
  if (max_dofs == planned_max_dofs_) return;
  planned_max_dofs_ = max_dofs;
  if (batches_) batches_->enable(max_dofs);
  std::vector<int> dense;
  dense_rows_.clear();
  for (int a = 0; a < model_.articulation_count; ++a) {
    const bool on_blocks = batches_ && batches_->active(a);
    route_[a] = on_blocks ? static_cast<StepRoute*>(batches_.get()) : dense_.get();
    if (on_blocks) continue;
    dense.push_back(a);
    if (art_[a].dof_count() > 0) dense_rows_.push_back(a);
  }
  for (int a = 0; a < model_.articulation_count; ++a)
    if (constrained_[a] && route_[a] == batches_.get()) dense_rows_.push_back(a);
  dense_->assign(dense);
}

StepContext SolverFeatherstone::begin_step(const State& in, State& out, const Control& control, Contacts& contacts,
                                           Scalar dt) {
  const int interval = settings.update_mass_matrix_interval;
  const bool refactor = steps_since_factor_ % interval == 0 || dt != factored_dt_ || !factor_kept_;
  steps_since_factor_ = refactor ? 1 : steps_since_factor_ + 1;
  if (refactor) factored_dt_ = dt;
  factor_kept_ = interval > 1;
  StepContext step;
  step.in = &in;
  step.out = &out;
  step.control = &control;
  step.contacts = &contacts;
  step.dt = dt;
  step.refactor = refactor;
  step.keep_factor = interval > 1;
  step.fuse = settings.fuse_cholesky;
  step.tile_gemm = settings.use_tile_gemm;
  step.keep = std::max<Scalar>(0, 1 - settings.angular_damping * dt);
  step.coriolis_implicitness = settings.coriolis_implicitness;
  step.aba_min_dofs = settings.aba_min_dofs;
  step.rows.pgs = {settings.num_iterations, settings.cfm, settings.friction_smoothing, settings.pgs_tolerance};
  step.rows.erp = settings.erp;
  step.rows.linear_slop = settings.linear_slop;
  step.rows.warmstarting_factor = settings.warmstarting_factor;
  step.rows.restitution_threshold = settings.restitution_threshold;
  step.rows.use_warmstarting = settings.use_warmstarting;
  step.divergence_speed = settings.divergence_speed;
  step.divergence_energy = settings.divergence_energy;
  step.energy_weight = energy_weight_.data();
  if (flagged_) std::fill(data_.flagged.begin(), data_.flagged.end(), 0);
  flagged_ = 0;
  step.flagged = data_.flagged.data();
  step.store_in_pass = settings.on_divergence != DivergencePolicy::Raise;
  step.stream = step_bytes_ > settings.stream_body_output_above;
  step.profile = settings.profile_stages;
  step.block_major = !settings.profile_stages;
  step.qd = data_.qd.data();
  step.q_next = data_.q_next.data();
  step.limit_impulse = data_.limit_impulse.data();
  step.pgs_converged = data_.pgs_converged.data();
  step.friction_impulse = data_.friction_impulse.data();
  step.equality_impulse = data_.equality_impulse.data();
  step.tendon_impulse = data_.tendon_impulse.data();
  step.diverged = data_.diverged.data();
  step.factor_failure = data_.factor_failure.data();
  trouble_ = 0;
  if (batches_) batches_->begin_step(step);
  lap_mark_ = settings.profile_stages ? now_ns() : 0;
  return step;
}

void SolverFeatherstone::list_contacts(const Contacts& contacts, StepContext& step) {
  const int n = contacts.contact_count, articulations = model_.articulation_count;
  if (n > counts_.contacts) {
    counts_.contacts = n;
    data_.allocate(counts_);
  }
  if (shape_contacts_.dt != step.dt) {  // the materials' pairs at this dt, where there are few materials
    const int m = shape_contacts_.material_count;
    shape_contacts_.dt = step.dt;
    if (m <= ShapeContacts::kPairTableMaterials) {
      contact_pairs_.resize(static_cast<size_t>(m) * m);
      for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b)
          contact_pairs_[m * a + b] =
              contact_pair(model_.friction_rule, contact_materials_[a], contact_materials_[b], step.dt);
      shape_contacts_.pairs = contact_pairs_.data();
    }
  }
  step.lists = {data_.contact_start.data(),
                data_.contact_list.data(),
                &model_,
                &index_,
                std::min(contact_dims_, contact_row_count(settings.max_condim)),
                &shape_contacts_};
  step.touched = data_.touched.data();
  island_contacts_.clear();
  island_articulations_ = dense_rows_;
  step.split = !island_articulations_.empty();
  if (n == 0 && listed_ == 0) return;  // the lists are empty already
  listed_ = n;
  // each contact to the unit of the articulation it moves (its units read the rest, engine/solver/blocks/rows.cpp),
  // else to the islands; a contact is owned in order where each owner's contacts follow the one before's, as the
  // collision pipeline lists a robot's worlds (then the lists are the contacts in order, made in parallel)
  const int threads = std::min(thread_count(), std::max(1, n / kContactsPerThread));
  const bool timed = settings.count_serial_time && threads > 1;  // (on one thread the regions are serial work)
  auto owner = [&](int c) {
    const int a = index_.moving(contacts.contact_body_a[c]), b = index_.moving(contacts.contact_body_b[c]);
    const int art = a >= 0 ? a : b;
    return art >= 0 && route_[art] == batches_.get() && !data_.touched[art] ? art : -1;
  };
  bool touched;
  int unordered = 0;
  {
    const ParallelTimer timer(timed, &serial_seconds_.parallel);
    touched = touch_articulations(contacts, threads);
    const Scalar too_deep = settings.divergence_depth;
    parallel_for(threads, n, [&](int c) {
      const int o = owner(c);
      data_.contact_owner[c] = o;
      if (contacts.contact_depth[c] > too_deep) flag_deep(contacts, c);
      if (o < 0 || (c > 0 && owner(c - 1) > o)) {
#pragma omp atomic write
        unordered = 1;
      }
    });
  }
  if (!unordered) {
    const ParallelTimer timer(timed, &serial_seconds_.parallel);
    // contact c starts the lists of the owners after c - 1's up to its own; the last ends the rest
    parallel_for(threads, n, [&](int c) {
      data_.contact_list[c] = c;
      const int before = c > 0 ? data_.contact_owner[c - 1] : -1;
      for (int a = before + 1; a <= data_.contact_owner[c]; ++a) data_.contact_start[a] = c;
      if (c == n - 1)
        for (int a = data_.contact_owner[c] + 1; a <= articulations; ++a) data_.contact_start[a] = n;
    });
    if (n == 0) std::fill_n(data_.contact_start.begin(), articulations + 1, 0);
  } else {
    group_by_key(
        n, articulations, [&](int c) { return data_.contact_owner[c]; }, data_.contact_start.data(),
        data_.contact_list.data(), data_.fill.data());
    for (int c = 0; c < n; ++c)
      if (data_.contact_owner[c] < 0) island_contacts_.push_back(c);
  }
  if (touched)
    for (int a = 0; a < articulations; ++a)
      if (data_.touched[a] && !constrained_[a] && route_[a] == batches_.get()) island_articulations_.push_back(a);
  step.split = !island_articulations_.empty() || !island_contacts_.empty();
}

void SolverFeatherstone::flag_deep(const Contacts& contacts, int c) {
  for (const int body : {contacts.contact_body_a[c], contacts.contact_body_b[c]}) {
    const int a = index_.moving(body);
    if (a < 0) continue;
#pragma omp atomic write
    data_.flagged[a] = 1;
  }
#pragma omp atomic write
  flagged_ = 1;
}

void SolverFeatherstone::flag_invalid(const int* arts, int count, const StepContext& step) {
  for (int i = 0; i < count; ++i) {
    if (input_valid(arts[i], step)) continue;
    data_.flagged[arts[i]] = 1;
#pragma omp atomic write
    flagged_ = 1;
  }
}

bool SolverFeatherstone::touch_articulations(const Contacts& contacts, int threads) {
  std::copy(constrained_.begin(), constrained_.end(), data_.touched.begin());
  int any = 0;
  int unexpected = -1;  // a contact joining bodies of two worlds
  parallel_for(threads, contacts.contact_count, [&](int c) {
    const int body_a = contacts.contact_body_a[c], body_b = contacts.contact_body_b[c];
    const int a = index_.moving(body_a), b = index_.moving(body_b);
    if (a < 0 || b < 0 || a == b) return;
    const int wa = model_.body_world[body_a], wb = model_.body_world[body_b];
    if (wa >= 0 && wb >= 0 && wa != wb) {
#pragma omp atomic write
      unexpected = c;
    }
#pragma omp atomic write
    data_.touched[a] = 1;
#pragma omp atomic write
    data_.touched[b] = 1;
#pragma omp atomic write
    any = 1;
  });
  if (unexpected >= 0) {
    const int body_a = contacts.contact_body_a[unexpected], body_b = contacts.contact_body_b[unexpected];
    fail("contact ", unexpected, " joins body ", body_a, " of world ", model_.body_world[body_a], " and body ", body_b,
         " of world ", model_.body_world[body_b], ": worlds never touch");
  }
  return any != 0;
}

void SolverFeatherstone::pass(const StepContext& step, Stage first, Stage last) {
  const int blocks = batches_ ? batches_->unit_count() : 0, units = blocks + dense_->unit_count();
  auto run = [&](Stage from, Stage to) {
    const ParallelTimer timer(settings.count_serial_time, &serial_seconds_.parallel);
    // float32 blocks flush subnormals (lanes.h: SubnormalsAsZero), the mode set once on each thread. A unit
    // clears its worlds' factor failures, notes whether they have wrenches and drives, then actuates and steps
    // them, and marks the step's trouble where one failed or diverged (else the guard reads no world)
    const bool factored = from == Stage::Dynamics, integrated = from <= Stage::Integrate && to >= Stage::Integrate;
    auto units_from = [&](int begin, int end) {
      UnitNotes notes;
      for (int u = begin; u < end; ++u) {
        StepRoute& route = u < blocks ? static_cast<StepRoute&>(*batches_) : *dense_;
        const int r = u < blocks ? u : u - blocks;
        int arts[kMostUnitArticulations];
        const int count = route.unit_articulations(r, arts);
        if (from != Stage::Dynamics) {
          route.run(r, from, to, step);
        } else {
          for (int i = 0; i < count; ++i) step.factor_failure[arts[i]] = -1;
          StepContext local = step;
          const bool invalid = u < blocks ? block_unit_notes(u, std::min(end, blocks), notes, local)
                                          : scan_unit(arts, count, local, nullptr);
          if (invalid) flag_invalid(arts, count, step);
          actuate_unit(arts, count, local);
          route.run(r, from, to, local);
        }
        bool failed = false;
        for (int i = 0; i < count; ++i)
          failed |= (factored & (step.factor_failure[arts[i]] >= 0)) | (integrated & (step.diverged[arts[i]] != 0));
        if (failed) {
#pragma omp atomic write
          trouble_ = 1;
        }
      }
    };
    auto done = [&] {
      if (step.stream) stream_fence();
    };
    const int threads = std::min(thread_count(), std::max(units, 1));
    if (model_.precision == Precision::Float32)
      parallel_runs<SubnormalsAsZero>(threads, units, units_from, done);
    else
      parallel_runs(threads, units, units_from, done);
  };
  if (step.block_major) {
    run(first, last);
    if (first == Stage::Dynamics) check_factors(step);
    return;
  }
  for (int s = static_cast<int>(first); s <= static_cast<int>(last); ++s) {
    const Stage stage = static_cast<Stage>(s);
    const RowPhaseSeconds before = batches_ ? batches_->row_phases() : RowPhaseSeconds{};
    const std::int64_t start = lap_mark_;
    run(stage, stage);
    if (stage == Stage::Dynamics) check_factors(step);
    if (stage != Stage::Rows) {
      lap(stage == Stage::Dynamics ? stage_seconds_.dynamics : stage_seconds_.integrate);
      continue;
    }
    // the rows stage's wall time shared out as its phases took the threads' time
    lap_mark_ = now_ns();
    const double wall = 1e-9 * static_cast<double>(lap_mark_ - start);
    const RowPhaseSeconds after = batches_ ? batches_->row_phases() : RowPhaseSeconds{};
    const double limits = after.limits - before.limits, contacts = after.contacts - before.contacts,
                 sweeps = after.sweeps - before.sweeps, sum = limits + contacts + sweeps;
    stage_seconds_.limit_rows += sum > 0 ? wall * limits / sum : 0;
    stage_seconds_.contact_rows += sum > 0 ? wall * contacts / sum : 0;
    stage_seconds_.solve += sum > 0 ? wall * sweeps / sum : wall;
  }
}

void SolverFeatherstone::solve_islands(const StepContext& step) {
  islands_->begin(route_);
  islands_->add_limit_rows(step, island_articulations_);
  islands_->add_friction_rows(step, island_articulations_);
  lap(stage_seconds_.limit_rows);
  islands_->add_contact_rows(step, island_contacts_);
  islands_->add_constraint_rows(step);
  lap(stage_seconds_.contact_rows);
  {
    const ParallelTimer timer(settings.count_serial_time, &serial_seconds_.parallel);
    islands_->solve(step, island_articulations_, island_contacts_, thread_count());
  }
  lap(stage_seconds_.solve);
}

void SolverFeatherstone::end_step(const State& in, State& out, const StepContext& step) {
  if (batches_) batches_->end_step(step);
  if (&out != &in) out.body_f = in.body_f;
  stage_seconds_.steps += settings.profile_stages;
}

void SolverFeatherstone::lap(double& total) {
  if (!settings.profile_stages) return;
  const std::int64_t now = now_ns();
  total += 1e-9 * static_cast<double>(now - lap_mark_);
  lap_mark_ = now;
}

}  // namespace novaphy
