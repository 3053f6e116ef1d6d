#include "engine/solver_featherstone.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>

#include "engine/dynamics.h"
#include "engine/error.h"
#include "engine/parallel.h"
#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/integrate.h"
#include "kernels/rnea.h"

namespace novaphy {

namespace {

// friction and restitution of a contact between shapes a and b
Scalar contact_mu(const Model& model, int a, int b) { return std::sqrt(model.shape_mu[a] * model.shape_mu[b]); }
Scalar contact_restitution(const Model& model, int a, int b) {
  return std::max(model.shape_restitution[a], model.shape_restitution[b]);
}

// items [0, n) grouped by key (in [0, buckets); a negative key leaves the item out), a counting sort:
// items[start[k] .. start[k + 1]) are key k's, ascending. `items` holds them all already; `next` is scratch
template <typename Key>
void group_by_key(int n, int buckets, Key key, std::vector<int>& start, std::vector<int>& items,
                  std::vector<int>& next) {
  start.assign(buckets + 1, 0);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) ++start[key(i) + 1];
  for (int k = 0; k < buckets; ++k) start[k + 1] += start[k];
  next.assign(start.begin(), start.end() - 1);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) items[next[key(i)]++] = i;
}

void check_range(const char* name, Scalar value, Scalar lo, Scalar hi) {
  if (!(value >= lo && value <= hi)) fail("settings.", name, " must be in [", lo, ", ", hi, "], got ", value);
}

}  // namespace

void SolverFeatherstoneSettings::check() const {
  constexpr Scalar inf = std::numeric_limits<Scalar>::infinity();
  if (num_iterations < 0) fail("settings.num_iterations must be >= 0, got ", num_iterations);
  if (num_threads < 0) fail("settings.num_threads must be >= 0, got ", num_threads);
  if (stream_body_output_above < 0)
    fail("settings.stream_body_output_above must be >= 0 bytes, got ", stream_body_output_above);
  if (aba_min_dofs < 0) fail("settings.aba_min_dofs must be >= 0, got ", aba_min_dofs);
  check_range("coriolis_implicitness", coriolis_implicitness, 0, 1);
  if (update_mass_matrix_interval < 1)
    fail("settings.update_mass_matrix_interval must be >= 1, got ", update_mass_matrix_interval);
  check_range("linear_slop", linear_slop, 0, 1e3);
  check_range("erp", erp, 0, 1);
  check_range("cfm", cfm, 0, 1e6);
  check_range("pgs_tolerance", pgs_tolerance, 0, 1e6);
  check_range("warmstarting_factor", warmstarting_factor, 0, 1);
  check_range("restitution_threshold", restitution_threshold, 0, 1e6);
  check_range("angular_damping", angular_damping, 0, inf);
  check_range("friction_smoothing", friction_smoothing, 0, 1);
  check_range("divergence_speed", divergence_speed, 0, inf);
  if (!std::isfinite(angular_damping)) fail("settings.angular_damping must be finite, got ", angular_damping);
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

SolverFeatherstone::SolverFeatherstone(const Model& model, const SolverFeatherstoneSettings& settings_)
    : settings(settings_), model_(model), welded_(weld_fixed_joints(model, settings_.weld_fixed_joints)) {
  settings.check();
  if (model.articulation_count == 0) fail("SolverFeatherstone needs a model with at least one articulation");
  const Model& kernel_model = welded_.welded_bodies.empty() ? model : welded_.model;
  for (int a = 0; a < model.articulation_count; ++a) {
    art_.push_back(kernel_model.articulation(a));
  }
  scratch_.resize(model.articulation_count);
  body_articulation_.assign(model.body_count, -1);
  body_link_.assign(model.body_count, -1);
  for (int j = 0; j < kernel_model.joint_count; ++j) {
    const int a = kernel_model.joint_articulation[j];
    body_articulation_[kernel_model.joint_child[j]] = a;
    body_link_[kernel_model.joint_child[j]] = j - kernel_model.articulation_start[a];
  }
  welded_into_.resize(model.articulation_count);
  for (const int b : welded_.welded_bodies) {
    body_articulation_[b] = body_articulation_[welded_.link_body[b]];
    body_link_[b] = body_link_[welded_.link_body[b]];
    welded_into_[body_articulation_[b]].push_back(b);
  }
  if (!welded_.welded_bodies.empty()) link_f_.assign(6 * model.body_count, 0);
  for (int j = 0; j < model.joint_count; ++j) {
    const auto type = static_cast<JointType>(model.joint_type[j]);
    const int dof = model.joint_qd_start[j];
    if (type == JointType::Revolute) rotational_dof_.push_back(dof);
    if ((type == JointType::Revolute || type == JointType::Prismatic) &&
        (std::isfinite(model.joint_limit_lower[dof]) || std::isfinite(model.joint_limit_upper[dof])))
      limited_joints_.push_back(j);
    if (type == JointType::Ball || type == JointType::Free)
      for (int k = 0; k < 3; ++k) rotational_dof_.push_back(dof + k);
  }
  std::stable_sort(limited_joints_.begin(), limited_joints_.end(),
                   [&](int x, int y) { return model.joint_articulation[x] < model.joint_articulation[y]; });
  limited_start_.assign(model.articulation_count + 1, 0);
  for (const int j : limited_joints_) ++limited_start_[model.joint_articulation[j] + 1];
  for (int a = 0; a < model.articulation_count; ++a) limited_start_[a + 1] += limited_start_[a];
  dof_articulation_.resize(model.joint_dof_count);
  for (int a = 0; a < model.articulation_count; ++a)
    std::fill_n(dof_articulation_.begin() + art_[a].qd_begin(), art_[a].dof_count(), a);
  dof_actuators_.resize(model.actuator_count);
  group_by_key(
      model.actuator_count, model.joint_dof_count, [&](int u) { return model.joint_qd_start[model.actuator_joint[u]]; },
      dof_actuator_start_, dof_actuators_, fill_);
  qd_.setZero(model.joint_dof_count);
  zero_.setZero(model.joint_dof_count);
  rhs_.setZero(model.joint_dof_count);
  q_next_.setZero(model.joint_coord_count);
  factor_failure_.assign(model.articulation_count, -1);
  factored_aba_.assign(model.articulation_count, 0);
  factored_batch_.assign(model.articulation_count, 0);
  implicit_lu_.resize(model.articulation_count);
  factored_diag_.resize(model.articulation_count);
  constant_H_.resize(model.articulation_count);  // filled by the first step
  constant_mass_.assign(model.articulation_count, 0);
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView& art = art_[a];
    bool constant = art.dof_count() > 0;
    for (int i = 0; i < art.link_count(); ++i)
      constant &= art.type(i) == JointType::Prismatic || art.type(i) == JointType::Fixed;
    constant_mass_[a] = constant;
  }
  diverged_.assign(model.articulation_count, 0);
  touched_.assign(model.articulation_count, 0);
  block_contact_start_.assign(model.articulation_count + 1, 0);
  // limit impulses kept per limited joint, in limited_joints_' order
  std::vector<int> limit_slot(model.joint_dof_count, -1);
  for (size_t m = 0; m < limited_joints_.size(); ++m)
    limit_slot[model.joint_qd_start[limited_joints_[m]]] = static_cast<int>(m);
  std::vector<std::uint8_t> batchable(model.articulation_count, 0);
  std::vector<std::vector<WeldedBody>> welded(model.articulation_count);
  for (int a = 0; a < model.articulation_count; ++a) {
    batchable[a] = art_[a].dof_count() > 0;
    for (const int b : welded_into_[a]) welded[a].push_back({b, body_link_[b], welded_.offset[b]});
  }
  for (int a = 0; a < model.articulation_count; ++a)
    if (!batchable[a]) unbatched_.push_back(a);
  if (unbatched_.size() < art_.size())
    batches_ =
        ArticulationBatches::make(kernel_model, art_, batchable, welded, model.body_com, limit_slot, model.precision);
  limit_row_.assign(2 * model.joint_dof_count, -1);
  // the impulses of the batched articulations' limits where the blocks read them as vectors, the others after
  limit_cell_.assign(2 * limited_joints_.size(), -1);
  int cells = 0;
  if (batches_) {
    const std::vector<int>& batched = batches_->limit_cells();
    std::copy(batched.begin(), batched.end(), limit_cell_.begin());
    cells = batches_->limit_cell_count();
  }
  for (int& cell : limit_cell_)
    if (cell < 0) cell = cells++;
  limit_impulse_.assign(cells, 0);
  step_bytes_ = static_cast<std::int64_t>(memory_bytes()) +
                static_cast<std::int64_t>(sizeof(Scalar)) * (model.joint_coord_count + model.joint_dof_count +
                                                             (7 + 6 + 6) * static_cast<std::int64_t>(model.body_count));
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

ArticulationScratch& SolverFeatherstone::scratch(int a) {
  if (scratch_[a].X_up.empty()) scratch_[a].resize(art_[a]);
  return scratch_[a];
}

std::size_t SolverFeatherstone::memory_bytes() const {
  std::size_t n = batches_ ? batches_->bytes() : 0;
  auto bytes = [](const auto& m) { return static_cast<std::size_t>(m.size()) * sizeof(Scalar); };
  for (const ArticulationScratch& s : scratch_) {
    n += (s.X_up.size() + s.X_world.size()) * sizeof(Transform) +
         (s.Xup.size() + s.I.size() + s.IC.size() + s.D_inv.size()) * sizeof(Mat6) +
         (s.c.size() + s.v.size() + s.a.size() + s.f.size() + s.pA.size()) * sizeof(Vec6);
    n += bytes(s.S) + bytes(s.U) + bytes(s.H) + bytes(s.S_world) + bytes(s.u) + bytes(s.C);
  }
  n += bytes(qd_) + bytes(q_next_) + bytes(rhs_) + bytes(zero_) + bytes(limit_impulse_);
  return n + limit_cell_.size() * sizeof(int);
}

template <typename F>
void SolverFeatherstone::for_each_articulation(F&& f) {
  // articulations are independent here: spread over threads by parallel_for, no shared writes
  const int count = static_cast<int>(art_.size());
  parallel_for(std::min(thread_count(), count), count, f);
}

void SolverFeatherstone::step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt) {
  check_step(in, out, control, contacts, dt);
  // each stage, timed into stage_seconds_ when profiling
  using Clock = std::chrono::steady_clock;
  Clock::time_point mark = settings.profile_stages ? Clock::now() : Clock::time_point{};
  auto lap = [&](double& total) {
    if (!settings.profile_stages) return;
    const Clock::time_point now = Clock::now();
    total += std::chrono::duration<double>(now - mark).count();
    mark = now;
  };
  // (a step with update_mass_matrix_interval 1 keeps no factor for the next: the blocks may make it
  // in scratch)
  const bool refactor =
      steps_since_factor_ % settings.update_mass_matrix_interval == 0 || dt != factored_dt_ || !factor_kept_;
  steps_since_factor_ = refactor ? 1 : steps_since_factor_ + 1;
  if (refactor) factored_dt_ = dt;
  factor_kept_ = settings.update_mass_matrix_interval > 1;
  batch_step_ = batches_ && settings.use_batch_kernels && settings.coriolis_implicitness == 0;
  if (batches_)
    batches_->enable(batch_step_ ? settings.aba_min_dofs : 0);  // off: factors go stale while the scalar kernels step
  all_on_batch_ = batch_step_ && batches_->active_count() == static_cast<int>(art_.size() - unbatched_.size());
  row_count_ = 0;
  pool_size_ = 0;
  scalar_rows_.clear();
  scalar_contacts_.clear();
  // articulations no contact joins to another moving one have their limit and contact rows solved in
  // their blocks
  const bool block_rows = batch_step_ && (!limited_joints_.empty() || contacts.contact_count > 0);
  if (block_rows) list_block_contacts(contacts);
  ArticulationBatches::BlockContacts block;
  block.contacts = &contacts;
  block.start = block_contact_start_.data();
  block.list = block_contacts_.data();
  block.link_a = contact_link_a_.data();
  block.link_b = contact_link_b_.data();
  block.mu = contact_mu_.data();
  block.restitution = contact_restitution_.data();
  ArticulationBatches::RowSettings rows;
  rows.pgs = pgs_settings();
  rows.erp = settings.erp;
  rows.linear_slop = settings.linear_slop;
  rows.warmstarting_factor = settings.warmstarting_factor;
  rows.restitution_threshold = settings.restitution_threshold;
  rows.use_warmstarting = settings.use_warmstarting;
  // every articulation in a block and every row solved there: the blocks step a block at a time, each
  // block's data in cache from its dynamics to its integration (profiling times the stages one after
  // another instead; the arithmetic is the same)
  fused_step_ = all_on_batch_ && scalar_contacts_.empty() && !settings.profile_stages;
  qd_in_ = in.joint_qd.data();
  std::fill(factor_failure_.begin(), factor_failure_.end(), -1);
  if (fused_step_) {
    batches_->step(in, control, control_forces(control), dt, dynamics_options(refactor, dt),
                   block_rows ? &block : nullptr, rows, qd_.data(), limit_impulse_.data(), q_next_.data(), divergence(),
                   factor_failure_.data(), stores_in_step() ? &out : nullptr, stream_body_output(), thread_count());
    std::fill(factored_batch_.begin(), factored_batch_.end(), 1);
    check_factors();
  } else {
    unconstrained_velocity(in, control, dt, refactor);
    lap(stage_seconds_.dynamics);
    if (block_rows) {
      batches_->solve_rows(in, touched_.data(), block, rows, dt, qd_.data(), limit_impulse_.data(), thread_count());
      for (int a = 0; a < static_cast<int>(art_.size()); ++a)
        if (!batches_->solves_rows(a, touched_.data())) scalar_rows_.push_back(a);
    } else {
      for (int a = 0; a < static_cast<int>(art_.size()); ++a) scalar_rows_.push_back(a);
      for (int c = 0; c < contacts.contact_count; ++c) scalar_contacts_.push_back(c);
    }
    build_limit_rows(in, dt);
    lap(stage_seconds_.limit_rows);
    build_contact_rows(contacts, dt);
    lap(stage_seconds_.contact_rows);
    solve_constraints(contacts);
    lap(stage_seconds_.solve);
  }
  integrate(in, out, dt);
  lap(stage_seconds_.integrate);
  stage_seconds_.steps += settings.profile_stages;
}

void SolverFeatherstone::check_step(const State& in, const State& out, const Control& control, const Contacts& contacts,
                                    Scalar dt) {
  if (!(dt > 0) || !std::isfinite(dt)) fail("dt must be finite and > 0, got ", dt);
  settings.check();
  model_.check(in);
  model_.check(out);
  model_.check(control);
  if (!same_layout(contacts, model_))
    fail("contacts buffer is from another model (", contacts.body_count, " bodies, ", contacts.shape_count,
         " shapes; the model has ", model_.body_count, " and ", model_.shape_count, ")");
  check_finite_step(in, control, &wrenches_, &drives_, thread_count());
}

bool SolverFeatherstone::stores_in_step() const {
  return fused_step_ && settings.on_divergence != DivergencePolicy::Raise;
}

bool SolverFeatherstone::stream_body_output() const { return step_bytes_ > settings.stream_body_output_above; }

ArticulationBatches::Divergence SolverFeatherstone::divergence() {
  ArticulationBatches::Divergence d;
  d.speed = settings.divergence_speed;
  d.diverged = diverged_.data();
  return d;
}

ArticulationBatches::DynamicsOptions SolverFeatherstone::dynamics_options(bool refactor, Scalar dt) const {
  ArticulationBatches::DynamicsOptions options;
  options.refactor = refactor;
  options.fuse = settings.fuse_cholesky;
  options.tile_gemm = settings.use_tile_gemm;
  options.wrenches = wrenches_;
  options.drives = drives_;
  options.keep = angular_keep(dt);
  options.keep_factor = settings.update_mass_matrix_interval > 1;
  return options;
}

const Scalar* SolverFeatherstone::control_forces(const Control& control) {
  // the blocks read joint_f itself when nothing adds to it and no scalar articulation writes over it
  if (model_.actuator_count == 0 && all_on_batch_) return control.joint_f.data();
  // control_force's sums, dof by dof (joint_f, then its actuators in order), the dofs in runs over the threads
  const int n = model_.joint_dof_count, runs = std::min(n, 16 * thread_count());
  const int *start = dof_actuator_start_.data(), *actuator = dof_actuators_.data();
  const Scalar* joint_f = control.joint_f.data();
  Scalar* tau = rhs_.data();
  parallel_for(thread_count(), runs, [&](int r) {
    const int end = static_cast<int>(static_cast<std::int64_t>(n) * (r + 1) / runs);
    for (int d = static_cast<int>(static_cast<std::int64_t>(n) * r / runs); d < end; ++d) {
      Scalar sum = joint_f[d];
      for (int k = start[d]; k < start[d + 1]; ++k) sum += actuator_force(model_, control, actuator[k]);
      tau[d] = sum;
    }
  });
  return rhs_.data();
}

void SolverFeatherstone::check_factors() const {
  for (size_t a = 0; a < art_.size(); ++a)
    if (factor_failure_[a] >= 0)
      fail("articulation ", a, ": mass matrix is not positive definite at dof ", factor_failure_[a],
           " (a massless link without children?)");
}

void SolverFeatherstone::unconstrained_velocity(const State& in, const Control& control, Scalar dt, bool refactor) {
  const Scalar* tau = control_forces(control);
  if (batch_step_)
    batches_->dynamics(in, control, tau, dt, dynamics_options(refactor, dt), qd_.data(), nullptr,
                       factor_failure_.data(), thread_count());

  for_each_articulation([&](int a) {
    if (on_batch(a)) {
      factored_batch_[a] = 1;
      return;
    }
    const ArticulationView& art = art_[a];
    ArticulationScratch& s = scratch(a);
    const int q0 = art.q_begin(), qd0 = art.qd_begin(), nv = art.dof_count();
    const Scalar* q = in.joint_q.data() + q0;
    const Scalar* qd = in.joint_qd.data() + qd0;
    forward_kinematics(art, q, s);
    forward_velocity(art, qd, s);
    for (int i = 0; i < art.link_count(); ++i)
      s.S_world.middleCols(art.qd_start(i), art.dof(i)) =
          motion_xform(s.X_world[i].inverse()) * s.S.middleCols(art.qd_start(i), art.dof(i));

    // rhs = tau - bias + springs, dampers and drives evaluated at the end of the step (implicit):
    // (H + dt D + dt^2 K) qdd = tau - bias - K_s (q + dt qd - q_ref) - D_s qd + ke (q_t - q - dt qd) + kd (v_t - qd)
    Scalar* rhs = rhs_.data() + qd0;
    rnea(art, zero_.data() + qd0, model_.gravity, link_wrenches(a, in.body_f.data()), s, s.u.data());
    for (int k = 0; k < nv; ++k) rhs[k] -= s.u[k];
    for (int i = 0; i < art.link_count(); ++i) {
      const JointType type = art.type(i);
      for (int m = 0; m < art.dof(i); ++m) {
        const int k = art.qd_start(i) + m, g = qd0 + k;
        const Scalar damping = model_.joint_damping[g], kd = control.joint_target_kd[g];
        // (the targets are read only when some gain is nonzero: unchecked otherwise)
        const Scalar target_vel = drives_ ? control.joint_target_vel[g] : qd[k];
        rhs[k] += -damping * qd[k] + kd * (target_vel - qd[k]);
        s.u[k] = dt * (damping + kd);  // diagonal added to H
        if (type != JointType::Revolute && type != JointType::Prismatic) continue;
        const int c = art.q_start(i);
        const Scalar stiffness = model_.joint_stiffness[g], ke = control.joint_target_ke[g];
        const Scalar q_end = q[c] + dt * qd[k];
        const Scalar target_pos = drives_ ? control.joint_target_pos[g] : q_end;
        rhs[k] += -stiffness * (q_end - model_.joint_q_ref[q0 + c]) + ke * (target_pos - q_end);
        s.u[k] += dt * dt * (stiffness + ke);
      }
    }

    // M = H + diag; qdd = M^-1 rhs. ABA factors in O(n) every step; H is factored every
    // update_mass_matrix_interval steps. With implicit Coriolis forces qdd = (M + theta dt C)^-1 rhs
    // (LU every step), and the constraint rows below still see M (its Cholesky factor).
    int bad = -1;
    const Scalar theta = settings.coriolis_implicitness;
    const bool use_aba = theta == 0 && nv >= settings.aba_min_dofs;
    // a constant H (Prismatic and Fixed joints only) is computed once; its factor is kept while
    // the implicit diagonal stays the same
    const bool constant = constant_mass_[a];
    const bool keep_factor =
        constant && theta == 0 && !factored_aba_[a] && factored_diag_[a].size() == nv && s.u == factored_diag_[a];
    if (use_aba) {
      const int link = aba_factor(art, s.u.data(), s);
      if (link < 0)
        aba_solve(art, s, rhs);
      else
        bad = art.qd_start(link);
    } else if (keep_factor || (!constant && !refactor && !factored_aba_[a] && !factored_batch_[a] && theta == 0)) {
      cholesky_solve(s.H, rhs);
    } else {
      if (constant && constant_H_[a].size() > 0) {
        s.H = constant_H_[a];
      } else {
        if (settings.use_tile_gemm)
          mass_matrix_gemm(art, s);
        else
          crba(art, s);
        if (constant) constant_H_[a] = s.H;
      }
      s.H.diagonal() += s.u;
      factored_diag_[a] = s.u;
      if (theta > 0) {
        bias_velocity_jacobian(art, qd, s, s.C);
        s.C = s.H + theta * dt * s.C;
        implicit_lu_[a].compute(s.C);
        s.tau_step = Eigen::Map<const VecX>(rhs, nv);
        Eigen::Map<VecX>(rhs, nv) = implicit_lu_[a].solve(s.tau_step);
        bad = cholesky_factor(s.H);
      } else if (settings.fuse_cholesky) {
        bad = cholesky_factor_solve(s.H, rhs);
      } else {
        bad = cholesky_factor(s.H);
        if (bad < 0) cholesky_solve(s.H, rhs);
      }
      if (bad >= 0) factored_diag_[a].resize(0);  // no factor to keep
    }
    factored_aba_[a] = use_aba;
    factored_batch_[a] = 0;
    factor_failure_[a] = bad < 0 ? -1 : qd0 + bad;
    qd_.segment(qd0, nv) = Eigen::Map<const VecX>(qd_in_ + qd0, nv) + dt * rhs_.segment(qd0, nv);
  });
  check_factors();
  // the blocks scale their own dofs
  const Scalar keep = angular_keep(dt);
  if (!all_on_batch_)
    for (const int dof : rotational_dof_)
      if (!on_batch(dof_articulation_[dof])) qd_[dof] *= keep;
}

int SolverFeatherstone::begin_row(int art_a, int art_b, RowKind kind, Scalar target) {
  if (row_count_ == static_cast<int>(rows_.size())) rows_.resize(std::max<size_t>(64, 2 * rows_.size()));
  PgsRow& row = rows_[row_count_];
  row = PgsRow{};
  row.kind = kind;
  row.target = target;
  row.side_count = 0;
  for (const int a : {art_b, art_a}) {
    if (a < 0 || (row.side_count == 1 && a == art_b)) continue;
    const int s = row.side_count++;
    row.dof_begin[s] = art_[a].qd_begin();
    row.dof_count[s] = art_[a].dof_count();
    row.pool[s] = pool_size_;
    pool_size_ += row.dof_count[s];
  }
  if (pool_size_ > static_cast<int>(J_.size())) {
    J_.resize(2 * pool_size_);
    MinvJT_.resize(2 * pool_size_);
  }
  for (int s = 0; s < row.side_count; ++s) std::fill_n(J_.begin() + row.pool[s], row.dof_count[s], 0);
  return row_count_++;
}

Scalar* SolverFeatherstone::row_jacobian(int r, int art) {
  PgsRow& row = rows_[r];
  for (int s = 0; s < row.side_count; ++s)
    if (row.dof_begin[s] == art_[art].qd_begin()) return J_.data() + row.pool[s];
  return nullptr;
}

void SolverFeatherstone::finish_row(int r) {
  PgsRow& row = rows_[r];
  Scalar W = 0;
  for (int s = 0; s < row.side_count; ++s) {
    Scalar* z = MinvJT_.data() + row.pool[s];
    const Scalar* J = J_.data() + row.pool[s];
    std::copy(J, J + row.dof_count[s], z);
    solve_mass(dof_articulation_[row.dof_begin[s]], z);
    for (int k = 0; k < row.dof_count[s]; ++k) W += J[k] * z[k];
  }
  row.inv_mass = W + settings.cfm > 1e-12 ? 1 / (W + settings.cfm) : 0;
}

void SolverFeatherstone::solve_mass(int a, Scalar* x) {
  if (on_batch(a))
    batches_->solve_mass(a, x);
  else if (factored_aba_[a])
    aba_solve(art_[a], scratch_[a], x);
  else
    cholesky_solve(scratch_[a].H, x);
}

void SolverFeatherstone::add_point_jacobian(int body, const Vec3& p, const Vec3& d, Scalar sign, Scalar* J) const {
  // J qd = d . (velocity of the body-fixed point at p) = sum over ancestor dofs of d . S_lin + (p x d) . S_ang
  const int a = body_articulation_[body];
  if (on_batch(a)) return batches_->point_jacobian(a, body_link_[body], p, d, sign, J);
  const ArticulationView& art = art_[a];
  const MatX& S = scratch_[a].S_world;
  const Vec3 pxd = p.cross(d);
  for (int i = body_link_[body]; i >= 0; i = art.parent(i))
    for (int k = art.qd_start(i); k < art.qd_start(i) + art.dof(i); ++k)
      J[k] += sign * (d.dot(S.col(k).tail<3>()) + pxd.dot(S.col(k).head<3>()));
}

int SolverFeatherstone::moving_articulation(int body) const {
  // a body of an articulation without dofs (welded to the world) is as static as the world
  return body >= 0 && art_[body_articulation_[body]].dof_count() > 0 ? body_articulation_[body] : -1;
}

void SolverFeatherstone::list_block_contacts(const Contacts& contacts) {
  // a contact joining two moving articulations puts both on the scalar path (touched_); every other
  // contact of an articulation whose rows its block solves is listed for it, in contact order. The
  // contacts' lookups on the threads, the lists in one pass after
  const int n = contacts.contact_count;
  if (static_cast<int>(block_contacts_.size()) < n) {
    for (auto* x : {&block_contacts_, &contact_link_a_, &contact_link_b_, &contact_block_}) x->resize(n);
    for (auto* x : {&contact_mu_, &contact_restitution_}) x->resize(n);
  }
  std::fill(touched_.begin(), touched_.end(), 0);
  auto touch = [&](int c) {
    const int a = moving_articulation(contacts.contact_body_a[c]);
    const int b = moving_articulation(contacts.contact_body_b[c]);
    if (a < 0 || b < 0 || a == b) return;
#pragma omp atomic write
    touched_[a] = 1;
#pragma omp atomic write
    touched_[b] = 1;
  };
  auto look_up = [&](int c) {
    const int ba = contacts.contact_body_a[c], bb = contacts.contact_body_b[c];
    const int a = moving_articulation(ba), b = moving_articulation(bb);
    const int art = a >= 0 ? a : b;
    contact_block_[c] = art >= 0 && on_batch(art) && !touched_[art] ? art : -1;
    if (contact_block_[c] < 0) return;
    contact_link_a_[c] = a >= 0 ? body_link_[ba] : -1;
    contact_link_b_[c] = b >= 0 ? body_link_[bb] : -1;
    const int sa = contacts.contact_shape_a[c], sb = contacts.contact_shape_b[c];
    contact_mu_[c] = contact_mu(model_, sa, sb);
    contact_restitution_[c] = contact_restitution(model_, sa, sb);
  };
  const int threads = std::min(thread_count(), n / 1024);
  parallel_for(threads, n, touch);
  parallel_for(threads, n, look_up);
  group_by_key(
      n, static_cast<int>(art_.size()), [&](int c) { return contact_block_[c]; }, block_contact_start_, block_contacts_,
      fill_);
  for (int c = 0; c < n; ++c)
    if (contact_block_[c] < 0) scalar_contacts_.push_back(c);
}

int SolverFeatherstone::add_row(int body_a, int body_b, const Vec3& p, const Vec3& d, RowKind kind, Scalar target) {
  const int art_a = moving_articulation(body_a), art_b = moving_articulation(body_b);
  const int r = begin_row(art_a, art_b, kind, target);
  if (art_b >= 0) add_point_jacobian(body_b, p, d, 1, row_jacobian(r, art_b));
  if (art_a >= 0) add_point_jacobian(body_a, p, d, -1, row_jacobian(r, art_a));
  return r;
}

void SolverFeatherstone::build_limit_rows(const State& in, Scalar dt) {
  // the limited joints of the articulations whose rows the scalar path builds
  auto for_each_limited = [&](auto&& f) {
    for (const int a : scalar_rows_)
      for (int m = limited_start_[a]; m < limited_start_[a + 1]; ++m) f(a, m);
  };
  for_each_limited([&](int, int m) {
    const int g = model_.joint_qd_start[limited_joints_[m]];
    limit_row_[2 * g] = limit_row_[2 * g + 1] = -1;
  });
  for_each_limited([&](int a, int m) {
    const int j = limited_joints_[m], g = model_.joint_qd_start[j];
    const Scalar q = in.joint_q[model_.joint_q_start[j]];
    for (int side = 0; side < 2; ++side) {
      // gap >= 0 inside the range; the row keeps sign * qd >= target
      const Scalar sign = side == 0 ? 1 : -1;
      const Scalar limit = side == 0 ? model_.joint_limit_lower[g] : model_.joint_limit_upper[g];
      if (!std::isfinite(limit)) continue;
      const Scalar gap = sign * (q - limit);
      if (gap + dt * sign * qd_[g] >= 0) continue;
      const Scalar target = gap >= 0 ? -gap / dt : settings.erp * std::max<Scalar>(-gap - settings.linear_slop, 0) / dt;
      const int r = begin_row(a, -1, RowKind::Unilateral, target);
      row_jacobian(r, a)[g - art_[a].qd_begin()] = sign;
      if (settings.use_warmstarting)
        rows_[r].lambda = settings.warmstarting_factor * limit_impulse_[limit_cell_[2 * m + side]];
      limit_row_[2 * g + side] = r;
    }
  });
}

void SolverFeatherstone::build_contact_rows(const Contacts& contacts, Scalar dt) {
  if (static_cast<int>(contact_row_.size()) < contacts.contact_count) contact_row_.resize(contacts.contact_count);
  for (const int c : scalar_contacts_) {
    const int sa = contacts.contact_shape_a[c], sb = contacts.contact_shape_b[c];
    const int ba = contacts.contact_body_a[c], bb = contacts.contact_body_b[c];
    const Vec3 p = Eigen::Map<const Vec3>(&contacts.contact_point[3 * c]);
    const Vec3 n = Eigen::Map<const Vec3>(&contacts.contact_normal[3 * c]);
    const Scalar depth = contacts.contact_depth[c];
    const Scalar mu = contact_mu(model_, sa, sb);
    const Scalar restitution = contact_restitution(model_, sa, sb);
    Vec3 t1, t2;
    contact_tangents(n, &t1, &t2);

    // normal row: push the penetration beyond the slop out at erp / dt, let a gap close in one step,
    // bounce at -restitution times the approach speed above the threshold
    const int rn = add_row(ba, bb, p, n, RowKind::Unilateral, 0);
    PgsRow& normal = rows_[rn];
    Scalar target = depth > settings.linear_slop ? settings.erp * (depth - settings.linear_slop) / dt
                                                 : std::min<Scalar>(depth, 0) / dt;
    // restitution only for a contact that closes within this step
    const Scalar v_approach = row_velocity(normal, J_, qd_in_);
    if (v_approach < -settings.restitution_threshold && depth - v_approach * dt >= 0)
      target = std::max(target, -restitution * v_approach);
    normal.target = target;
    const int r1 = add_row(ba, bb, p, t1, RowKind::FrictionPair, 0);
    const int r2 = add_row(ba, bb, p, t2, RowKind::FrictionPair, 0);
    rows_[r1].normal = rn;
    rows_[r1].mu = mu;

    const Scalar* previous = contacts.previous(c);
    if (settings.use_warmstarting && previous) {
      const Vec3 P = settings.warmstarting_factor * Eigen::Map<const Vec3>(previous);
      rows_[rn].lambda = std::max<Scalar>(0, P.dot(n));
      rows_[r1].lambda = P.dot(t1);
      rows_[r2].lambda = P.dot(t2);
    }
    contact_row_[c] = rn;
  }
}

void SolverFeatherstone::group_islands() {
  // articulations joined by rows (union-find), then each island's rows in row order
  island_parent_.resize(art_.size());
  std::iota(island_parent_.begin(), island_parent_.end(), 0);
  auto find = [&](int a) {
    while (island_parent_[a] != a) a = island_parent_[a] = island_parent_[island_parent_[a]];
    return a;
  };
  auto art_of = [&](const PgsRow& row, int side) { return dof_articulation_[row.dof_begin[side]]; };
  for (int r = 0; r < row_count_; ++r)
    if (rows_[r].side_count == 2) {
      const int x = find(art_of(rows_[r], 0)), y = find(art_of(rows_[r], 1));
      island_parent_[std::max(x, y)] = std::min(x, y);
    }
  island_of_row_.resize(row_count_);
  for (int r = 0; r < row_count_; ++r)
    island_of_row_[r] = rows_[r].side_count > 0 ? find(art_of(rows_[r], 0)) : 0;  // a row of no dofs does nothing
  island_rows_.resize(row_count_);
  group_by_key(
      row_count_, static_cast<int>(art_.size()), [&](int r) { return island_of_row_[r]; }, island_start_, island_rows_,
      fill_);
}

PgsSettings SolverFeatherstone::pgs_settings() const {
  PgsSettings pgs;
  pgs.iterations = settings.num_iterations;
  pgs.cfm = settings.cfm;
  pgs.friction_smoothing = settings.friction_smoothing;
  pgs.tolerance = settings.pgs_tolerance;
  return pgs;
}

void SolverFeatherstone::solve_islands() {
  // islands of articulations joined by rows are independent: each one's rows get M^-1 J^T, their
  // warm start and the PGS sweeps in row order on one thread, islands in parallel (the same bits
  // as one sweep over all rows)
  group_islands();
  const PgsSettings pgs = pgs_settings();
  for_each_articulation([&](int island) {
    const int begin = island_start_[island], count = island_start_[island + 1] - begin;
    const int* order = island_rows_.data() + begin;
    for (int k = 0; k < count; ++k) finish_row(order[k]);
    for (int k = 0; k < count; ++k) apply_impulse(rows_[order[k]], MinvJT_, rows_[order[k]].lambda, qd_.data());
    pgs_solve(rows_, order, count, J_, MinvJT_, pgs, qd_.data());
  });
}

void SolverFeatherstone::solve_constraints(Contacts& contacts) {
  if (row_count_ > 0) solve_islands();  // nothing to solve without rows

  // impulses kept for warm starting: contacts as world vectors on body b, limits per dof and side
  for (const int c : scalar_contacts_) {
    const int rn = contact_row_[c];
    const Vec3 n = Eigen::Map<const Vec3>(&contacts.contact_normal[3 * c]);
    Vec3 t1, t2;
    contact_tangents(n, &t1, &t2);
    const Vec3 impulse = rows_[rn].lambda * n + rows_[rn + 1].lambda * t1 + rows_[rn + 2].lambda * t2;
    Eigen::Map<Vec3>(&contacts.contact_impulse[3 * c]) = impulse.allFinite() ? impulse : Vec3::Zero();
  }
  for (const int a : scalar_rows_)  // the blocks kept the others' impulses
    for (int m = limited_start_[a]; m < limited_start_[a + 1]; ++m) {
      const int g = model_.joint_qd_start[limited_joints_[m]];
      for (int side = 0; side < 2; ++side) {
        const int r = limit_row_[2 * g + side];
        const Scalar lambda = r < 0 ? 0 : rows_[r].lambda;
        limit_impulse_[limit_cell_[2 * m + side]] = std::isfinite(lambda) ? lambda : 0;
      }
    }
}

void SolverFeatherstone::integrate(const State& in, State& out, Scalar dt) {
  // divergence guard: an articulation whose state went non-finite or beyond divergence_speed is
  // flagged, and raised, kept as it was (Flag) or reset to the model's initial state (Reset)
  // (the blocks integrate and test their own articulations)
  if (batch_step_ && !fused_step_)
    batches_->integrate(in, qd_.data(), dt, q_next_.data(), divergence(), thread_count());
  // with every articulation of dofs in a block, the loops below visit only those without dofs (and, for
  // the guard, the blocks' flagged ones): no parallel region for a pass that would do nothing
  auto for_each_unbatched = [&](auto&& f) {
    if (!all_on_batch_) return for_each_articulation(f);
    for (const int a : unbatched_) f(a);
  };
  auto for_each_to_visit = [&](auto&& f) {
    for_each_unbatched(f);
    if (all_on_batch_ && settings.on_divergence != DivergencePolicy::Raise)
      for (int a = 0; a < static_cast<int>(art_.size()); ++a)
        if (diverged_[a] && on_batch(a)) f(a);
  };
  // out.joint_q, joint_qd, body_q and body_qd of articulation a from q_next_ and qd_, in double
  auto store = [&](int a) {
    const ArticulationView& art = art_[a];
    std::copy_n(q_next_.data() + art.q_begin(), art.coord_count(), out.joint_q.begin() + art.q_begin());
    std::copy_n(qd_.data() + art.qd_begin(), art.dof_count(), out.joint_qd.begin() + art.qd_begin());
    ArticulationScratch& s = scratch(a);
    forward_kinematics(art, out.joint_q.data() + art.q_begin(), s);
    forward_velocity(art, out.joint_qd.data() + art.qd_begin(), s);
    store_bodies(a, out);
  };
  for_each_to_visit([&](int a) {
    const ArticulationView& art = art_[a];
    const int q0 = art.q_begin(), qd0 = art.qd_begin(), nq = art.coord_count(), nv = art.dof_count();
    if (!on_batch(a)) {
      integrate_joints(art, in.joint_q.data() + q0, qd_.data() + qd0, dt, q_next_.data() + q0);
      const auto q = q_next_.segment(q0, nq);
      const auto qd = qd_.segment(qd0, nv);
      diverged_[a] =
          !q.allFinite() || !qd.allFinite() || (nv > 0 && qd.cwiseAbs().maxCoeff() > settings.divergence_speed);
    }
    if (!diverged_[a] || settings.on_divergence == DivergencePolicy::Raise) return;
    const bool keep = settings.on_divergence == DivergencePolicy::Flag;  // the input state is finite
    for (int k = 0; k < nq; ++k) q_next_[q0 + k] = keep ? in.joint_q[q0 + k] : model_.joint_q0[q0 + k];
    for (int k = 0; k < nv; ++k) qd_[qd0 + k] = keep ? in.joint_qd[qd0 + k] : 0;
    // (the blocks left out the worlds they flagged; out may be in, whose state Flag keeps)
    if (stores_in_step() && on_batch(a)) store(a);
  });
  if (settings.on_divergence == DivergencePolicy::Raise)
    for (size_t a = 0; a < art_.size(); ++a)
      if (diverged_[a])
        fail("step diverged in articulation ", a, " (a non-finite state or a speed beyond ", settings.divergence_speed,
             "; dt ", dt, " too large for the model's stiffness or forces?)");
  if (&out != &in) out.body_f = in.body_f;
  // (the blocks copy their own articulations' coordinates out with their bodies)
  if (batch_step_ && !stores_in_step())
    batches_->store_bodies(q_next_.data(), qd_.data(), out, stream_body_output(), thread_count());
  for_each_unbatched([&](int a) {
    if (!on_batch(a)) store(a);
  });
}

void SolverFeatherstone::store_bodies(int a, State& out) const {
  // each body at its own centre of mass (the model's, not the merged link's)
  const ArticulationView& art = art_[a];
  auto com = [&](int b) { return Vec3(Eigen::Map<const Vec3>(&model_.body_com[3 * b])); };
  for (int i = 0; i < art.link_count(); ++i)
    store_body(scratch_[a], i, Transform::identity(), com(art.body(i)), art.body(i), out);
  for (const int b : welded_into_[a]) store_body(scratch_[a], body_link_[b], welded_.offset[b], com(b), b, out);
}

const Scalar* SolverFeatherstone::link_wrenches(int a, const Scalar* body_f) {
  if (welded_into_[a].empty()) return body_f;
  const ArticulationView& art = art_[a];
  const ArticulationScratch& s = scratch_[a];
  auto pushed = [&](int b) { return Eigen::Map<const Vec6>(body_f + 6 * b).any(); };
  bool any = false;
  for (int i = 0; i < art.link_count() && !any; ++i) any = pushed(art.body(i));
  for (size_t k = 0; k < welded_into_[a].size() && !any; ++k) any = pushed(welded_into_[a][k]);
  if (!any) return body_f;
  // a wrench [f at the body's centre of mass; torque] moves to the link's merged centre of mass
  auto add = [&](int b, int link, const Transform& offset) {
    const Transform& X = s.X_world[link];
    const Vec3 c_body = X.apply(offset.apply(Eigen::Map<const Vec3>(&model_.body_com[3 * b])));
    const Vec3 c_link = X.apply(art.com(link));
    const Vec3 f = Eigen::Map<const Vec3>(body_f + 6 * b);
    Scalar* out = link_f_.data() + 6 * art.body(link);
    Eigen::Map<Vec3>(out) += f;
    Eigen::Map<Vec3>(out + 3) += Eigen::Map<const Vec3>(body_f + 6 * b + 3) + (c_body - c_link).cross(f);
  };
  for (int i = 0; i < art.link_count(); ++i) std::fill_n(link_f_.data() + 6 * art.body(i), 6, 0);
  for (int i = 0; i < art.link_count(); ++i) add(art.body(i), i, Transform::identity());
  for (const int b : welded_into_[a]) add(b, body_link_[b], welded_.offset[b]);
  return link_f_.data();
}

}  // namespace novaphy
