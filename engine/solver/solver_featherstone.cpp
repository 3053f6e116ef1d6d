#include "engine/solver/solver_featherstone.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <type_traits>

#include "engine/model/actuator.h"
#include "engine/model/error.h"
#include "engine/solver/joint_support.h"
#include "engine/solver/parts/rows.h"
#include "engine/threads/parallel.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/stream.h"

namespace novaphy {

namespace {

// no thread wakes in the contact lists for fewer contacts (a parallel region costs about as much)
constexpr int kContactsPerThread = 512;

}  // namespace

JointSupportMatrix SolverFeatherstone::joint_support() const {
  return novaphy::joint_support("SolverFeatherstone", false);
}

// ---- made once: the routes and their data over what is built once for the model (SolverModel)

SolverFeatherstone::SolverFeatherstone(const Model& model, const SolverFeatherstoneSettings& settings_)
    : settings(settings_),
      model_(model),
      built_(supported_model(model, "SolverFeatherstone", false), settings_.weld_fixed_joints),
      parameters_read_(model.parameter_writes),
      sensors_(model) {
  settings.check();
  max_threads_ = std::max(1, omp_get_max_threads());
  model_wrenches_ = ModelWrenches::of(model);
  if (model.articulation_count == 0) fail("SolverFeatherstone needs a model with at least one articulation");
  shape_contacts_ = {built_.contact_materials.data(),
                     built_.shape_material.data(),
                     built_.shape_weight.data(),
                     nullptr,
                     static_cast<int>(built_.contact_materials.size()),
                     model.friction_rule,
                     0};
  // limits kept per limited joint, by articulation: the blocks lay out their articulations' cells, the
  // others follow
  std::vector<std::uint8_t> batchable(model.articulation_count, 0);
  for (int a = 0; a < model.articulation_count; ++a) batchable[a] = built_.art[a].dof_count() > 0;
  const Model& kernel_model = built_.welded.welded_bodies.empty() ? model : built_.welded.model;
  if (std::find(batchable.begin(), batchable.end(), 1) != batchable.end())
    batches_ = ArticulationBatches::make(kernel_model, built_.art, batchable, built_.welded_into, model.body_com,
                                         built_.limit_slot, model.precision);
  limit_cell_.assign(2 * built_.limited_joints.size(), -1);
  int cells = 0;
  if (batches_) {
    const std::vector<int>& batched = batches_->limit_cells();
    std::copy(batched.begin(), batched.end(), limit_cell_.begin());
    cells = batches_->limit_cell_count();
  }
  for (int& cell : limit_cell_)
    if (cell < 0) cell = cells++;
  dense_ = std::make_unique<DenseArticulations>(model, built_.art, built_.welded_into);
  islands_ = std::make_unique<IslandRows>(model, built_.art, built_.index, built_.limited_joints, built_.limited_start,
                                          limit_cell_);
  route_.assign(model.articulation_count, nullptr);
  counts_ = {model.joint_dof_count, model.joint_coord_count, model.articulation_count, cells, 0,
             model.tendon_count,    model.equality_count};
  data_.allocate(counts_);
  std::fill(data_.factor_failure.begin(), data_.factor_failure.end(), -1);
  std::copy(built_.constrained.begin(), built_.constrained.end(), data_.touched.begin());
  reset_q_ = model.joint_q0;
  reset_qd_.assign(model.joint_dof_count, 0);
  unit_seconds_.resize(max_threads_);
  step_bytes_ = static_cast<std::int64_t>(memory_bytes()) +
                static_cast<std::int64_t>(sizeof(Scalar)) * (model.joint_coord_count + model.joint_dof_count +
                                                             (7 + 6 + 6) * static_cast<std::int64_t>(model.body_count));
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

std::size_t SolverFeatherstone::memory_bytes() const {
  std::size_t n = (batches_ ? batches_->bytes() : 0) + dense_->bytes() + islands_->bytes() + data_.bytes();
  return n + (limit_cell_.size() + built_.limited_joints.size()) * sizeof(int);
}

int SolverFeatherstone::thread_count() const {
  // no more than the threads the routes keep scratch for (OpenMP's count when the solver was made)
  return std::clamp(settings.num_threads > 0 ? settings.num_threads : omp_get_max_threads(), 1, max_threads_);
}

// ---- the step

void SolverFeatherstone::step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt) {
  const ExclusiveCall exclusive(busy_, "SolverFeatherstone.step");
  const std::int64_t start = settings.count_serial_time ? now_ns() : 0;
  // check the arguments; the inputs: the routes planned, the step's options, the actuators' joint forces; each
  // contact to its unit or the islands; then the stages in physics order (route.h: kinematics and forces, mass and
  // factor; rows and solve; the islands; integrate; guard; store)
  check_step(in, out, control, contacts, dt);
  // the sensors read what the start decides before the step; where they read accelerations or forces, the start's
  // coordinates and velocities after it: in's own, or a copy of those the step overwrites (in is out); body_f the
  // step leaves as it was
  sensors_.read_start(in, thread_count());
  const bool keep_start = sensors_.reads_dynamics() && &in == &out;
  if (keep_start) {
    start_q_ = in.joint_q;
    start_qd_ = in.joint_qd;
  }
  const Scalar* start_q = keep_start ? start_q_.data() : in.joint_q.data();
  const Scalar* start_qd = keep_start ? start_qd_.data() : in.joint_qd.data();
  read_parameters();
  plan();
  StepContext step = begin_step(in, out, control, contacts, dt);
  actuate(control, step);
  list_contacts(contacts, step);
  run_stages(step);
  end_step(in, out, step);
  sensors_.evaluate(start_q, start_qd, out.joint_qd.data(), out.body_f.data(), contacts, dt, out.sensor_data.data(),
                    thread_count());
  restart_guard_resets(out);
  if (!settings.count_serial_time) return;
  serial_seconds_.step += 1e-9 * static_cast<double>(now_ns() - start);
  ++serial_seconds_.steps;
}

void SolverFeatherstone::run_stages(const StepContext& step) {
  // the unit stages since the last step's stage they wait for make one pass; a step's stage they do not wait for
  // follows the last pass
  std::optional<Stage> first;
  Stage last = Stage::Dynamics;
  std::array<Stage, std::size(kStages)> after_pass;
  int after_pass_count = 0;
  for (const Stage s : kStages) {
    if (unit_stage(s)) {
      if (!first) first = s;
      last = s;
    } else if (step.runs(s) && !step.waits_for(s)) {
      after_pass[after_pass_count++] = s;
    } else if (step.runs(s)) {
      if (first) pass(step, *first, last);
      first.reset();
      step_stage(s, step);
    }
  }
  if (first) pass(step, *first, last);
  for (int i = 0; i < after_pass_count; ++i) step_stage(after_pass[i], step);
}

void SolverFeatherstone::step_stage(Stage s, const StepContext& step) {
  if (s == Stage::Islands)
    solve_islands(step);
  else
    guard(step);
}

void SolverFeatherstone::read_parameters() {
  if (model_.parameter_writes == parameters_read_) return;
  std::vector<std::uint8_t> worlds(model_.world_count), articulations(model_.articulation_count);
  for (int w = 0; w < model_.world_count; ++w) worlds[w] = model_.world_parameter_write[w] > parameters_read_;
  for (int a = 0; a < model_.articulation_count; ++a) articulations[a] = worlds[model_.articulation_world(a)];
  parameters_read_ = model_.parameter_writes;
  built_.read_parameters(model_, worlds, thread_count());
  if (batches_)
    batches_->read_parameters(built_.welded.welded_bodies.empty() ? model_ : built_.welded.model, model_.body_com,
                              articulations, thread_count());
  // the contact materials' pairs made again at the next dt (ShapeContacts: one material per shape now)
  shape_contacts_.materials = built_.contact_materials.data();
  shape_contacts_.material_count = static_cast<int>(built_.contact_materials.size());
  shape_contacts_.pairs = nullptr;
  shape_contacts_.dt = 0;
  factor_kept_ = false;
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
    if (built_.art[a].dof_count() > 0) dense_rows_.push_back(a);
  }
  for (int a = 0; a < model_.articulation_count; ++a)
    if (built_.constrained[a] && route_[a] == batches_.get()) dense_rows_.push_back(a);
  dense_->assign(dense);
}

void SolverFeatherstone::forget_reset_worlds(const State& in) {
  if (std::find(in.world_reset.begin(), in.world_reset.end(), 1) == in.world_reset.end()) return;
  auto reset = [&](int a) {
    const int w = a >= 0 ? model_.articulation_world(a) : -1;
    return w >= 0 && in.world_reset[w];
  };
  for (int a = 0; a < model_.articulation_count; ++a) {
    if (!reset(a)) continue;
    data_.pgs_converged[a] = 0;
    const ArticulationView& art = built_.art[a];
    std::fill_n(data_.friction_impulse.begin() + art.qd_begin(), art.dof_count(), Scalar(0));
    for (int m = built_.limited_start[a]; m < built_.limited_start[a + 1]; ++m)
      for (int side = 0; side < 2; ++side) data_.limit_impulse[limit_cell_[2 * m + side]] = 0;
  }
  for (int e = 0; e < model_.equality_count; ++e)
    if (reset(built_.equality_articulation[e])) std::fill_n(data_.equality_impulse.begin() + 6 * e, 6, Scalar(0));
  for (int t = 0; t < model_.tendon_count; ++t)
    if (reset(built_.tendon_articulation[t])) std::fill_n(data_.tendon_impulse.begin() + 3 * t, 3, Scalar(0));
  factor_kept_ = false;
}

StepContext SolverFeatherstone::begin_step(const State& in, State& out, const Control& control, Contacts& contacts,
                                           Scalar dt) {
  forget_reset_worlds(in);
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
  step.body_f = in.body_f.data();
  if (model_wrenches_.any()) {
    applied_wrenches(model_, model_wrenches_, in, &control, applied_body_f_);
    step.body_f = applied_body_f_.data();
  }
  step.settings = settings;
  step.refactor = refactor;
  step.keep = std::max<Scalar>(0, 1 - settings.angular_damping * dt);
  step.stream = step_bytes_ > settings.stream_body_output_above;
  step.pgs = {settings.num_iterations, settings.cfm, settings.friction_smoothing, settings.pgs_tolerance};
  step.energy_weight = built_.energy_weight.data();
  if (flagged_) std::fill(data_.flagged.begin(), data_.flagged.end(), 0);
  flagged_ = 0;
  step.flagged = data_.flagged.data();
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
              contact_pair(model_.friction_rule, built_.contact_materials[a], built_.contact_materials[b], step.dt);
      shape_contacts_.pairs = contact_pairs_.data();
    }
  }
  step.lists = {data_.contact_start.data(),
                data_.contact_list.data(),
                &model_,
                &built_.index,
                std::min(built_.contact_dims, ContactRows::count(settings.max_condim)),
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
    const int a = built_.index.moving(contacts.contact_body_a[c]), b = built_.index.moving(contacts.contact_body_b[c]);
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
      if (data_.touched[a] && !built_.constrained[a] && route_[a] == batches_.get()) island_articulations_.push_back(a);
  step.split = !island_articulations_.empty() || !island_contacts_.empty();
}

void SolverFeatherstone::flag_deep(const Contacts& contacts, int c) {
  for (const int body : {contacts.contact_body_a[c], contacts.contact_body_b[c]}) {
    const int a = built_.index.moving(body);
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
  std::copy(built_.constrained.begin(), built_.constrained.end(), data_.touched.begin());
  int any = 0;
  int unexpected = -1;  // a contact joining bodies of two worlds
  parallel_for(threads, contacts.contact_count, [&](int c) {
    const int body_a = contacts.contact_body_a[c], body_b = contacts.contact_body_b[c];
    const int a = built_.index.moving(body_a), b = built_.index.moving(body_b);
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
  const bool profile = settings.profile_stages;
  const RowPhaseSeconds phases = profile && batches_ ? batches_->row_phases() : RowPhaseSeconds{};
  if (profile) std::fill(unit_seconds_.begin(), unit_seconds_.end(), UnitStageSeconds{});
  // float32 blocks flush subnormals (lanes.h: SubnormalsAsZero), the mode set once on each thread. A unit's
  // Dynamics clears its worlds' factor failures, notes whether they have wrenches and drives, then actuates and
  // steps them; a unit marks the step's trouble where one failed or diverged (else the guard reads no world)
  const bool factored = first == Stage::Dynamics, integrated = first <= Stage::Integrate && last >= Stage::Integrate;
  auto units_from = [&](int begin, int end) {
    UnitNotes notes;
    UnitStageSeconds* seconds = profile ? &unit_seconds_[omp_get_thread_num()] : nullptr;
    for (int u = begin; u < end; ++u) {
      StepRoute& route = u < blocks ? static_cast<StepRoute&>(*batches_) : *dense_;
      const int r = u < blocks ? u : u - blocks;
      int arts[kMostUnitArticulations];
      const int count = route.unit_articulations(r, arts);
      UnitInputs inputs;
      if (factored) {
        for (int i = 0; i < count; ++i) step.factor_failure[arts[i]] = -1;
        const bool invalid = u < blocks ? block_unit_notes(u, std::min(end, blocks), step, notes, inputs)
                                        : scan_unit(arts, count, step, inputs, nullptr);
        if (invalid) flag_invalid(arts, count, step);
        actuate_unit(arts, count, step, inputs);
      }
      run_unit(route, {r, first, last}, step, inputs, seconds);
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
  {
    const ParallelTimer timer(settings.count_serial_time, &serial_seconds_.parallel);
    const int threads = std::min(thread_count(), std::max(units, 1));
    if (model_.precision == Precision::Float32)
      parallel_runs<SubnormalsAsZero>(threads, units, units_from, done);
    else
      parallel_runs(threads, units, units_from, done);
  }
  if (factored) check_factors(step);
  if (profile) lap_pass(phases);
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
  std::fill(out.world_reset.begin(), out.world_reset.end(), 0);
  stage_seconds_.steps += settings.profile_stages;
}

void SolverFeatherstone::restart_guard_resets(State& out) const {
  if (!trouble_ || settings.on_divergence != DivergencePolicy::Reset) return;
  for (int a = 0; a < model_.articulation_count; ++a) {
    const int w = model_.articulation_world(a);
    if (!data_.diverged[a] || w < 0) continue;
    out.world_reset[w] = 1;
    for (int s = 0; s < model_.sensor_count; ++s)
      if (model_.sensor_world[s] == w)
        std::fill(out.sensor_data.begin() + model_.sensor_start[s],
                  out.sensor_data.begin() + model_.sensor_start[s + 1], 0);
  }
}

void SolverFeatherstone::lap(double& total) {
  if (!settings.profile_stages) return;
  const std::int64_t now = now_ns();
  total += 1e-9 * static_cast<double>(now - lap_mark_);
  lap_mark_ = now;
}

void SolverFeatherstone::lap_pass(const RowPhaseSeconds& before) {
  const std::int64_t now = now_ns();
  const double wall = 1e-9 * static_cast<double>(now - lap_mark_);
  lap_mark_ = now;
  UnitStageSeconds sum;
  for (const UnitStageSeconds& t : unit_seconds_) {
    sum.dynamics += t.dynamics;
    sum.rows += t.rows;
    sum.integrate += t.integrate;
  }
  const double total = sum.dynamics + sum.rows + sum.integrate, scale = total > 0 ? wall / total : 0;
  stage_seconds_.dynamics += scale * sum.dynamics;
  stage_seconds_.integrate += scale * sum.integrate;
  // the rows stage's share shared out as its phases took the threads' time
  const double rows = scale * sum.rows;
  const RowPhaseSeconds after = batches_ ? batches_->row_phases() : RowPhaseSeconds{};
  const double limits = after.limits - before.limits, contacts = after.contacts - before.contacts,
               sweeps = after.sweeps - before.sweeps, phases = limits + contacts + sweeps;
  stage_seconds_.limit_rows += phases > 0 ? rows * limits / phases : 0;
  stage_seconds_.contact_rows += phases > 0 ? rows * contacts / phases : 0;
  stage_seconds_.solve += phases > 0 ? rows * sweeps / phases : rows;
}

}  // namespace novaphy
