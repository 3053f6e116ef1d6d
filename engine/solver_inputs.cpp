// SolverFeatherstone, what a step reads: its arguments checked, each unit's notes of wrenches and drives, the
// joint forces of actuators and tendons, and a world whose output went wrong traced to a non-finite input
// (docs/errors.md). The rest of the solver: solver_featherstone.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "engine/dynamics.h"
#include "engine/error.h"
#include "engine/parts/actuator.h"
#include "engine/parts/tendon.h"
#include "engine/solver_featherstone.h"

namespace novaphy {

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
  bool loose_finite = true;
  for (const int b : loose_bodies_)
    for (int k = 0; k < 6; ++k) loose_finite &= std::isfinite(in.body_f[6 * static_cast<size_t>(b) + k]);
  for (const int u : loose_actuators_) loose_finite &= std::isfinite(control.actuator_ctrl[u]);
  if (loose_finite) return;
  bool wrenches, drives;
  check_finite_step(in, control, &wrenches, &drives);  // throws naming the first non-finite entry
}

namespace {

// the entries of one array a unit reads, in ranges joined where one starts as the last ended (a block's worlds
// lie one after another), scanned a run at a time (scan_bits, as check_finite_step's)
class RunScan {
 public:
  RunScan(const std::vector<Scalar>& x, std::uint64_t* bad) : x_(x), bad_(bad) {}
  void add(int begin, int count) {
    if (begin != end_) flush();
    if (begin != end_) begin_ = begin;
    end_ = begin + count;
  }
  // scans what is pending; returns whether any entry scanned so far is nonzero
  bool flush() {
    scan_bits(x_.data(), begin_, end_, bad_, &nonzero_);
    begin_ = end_;
    return nonzero_ != 0;
  }

 private:
  const std::vector<Scalar>& x_;
  std::uint64_t* bad_;
  std::uint64_t nonzero_ = 0;
  int begin_ = 0, end_ = 0;
};

}  // namespace

void SolverFeatherstone::scan_unit(const int* arts, int count, StepContext& local, bool* finite) const {
  const State& in = *local.in;
  const Control& control = *local.control;
  std::uint64_t bad = 0;
  RunScan ke(control.joint_target_ke, &bad), kd(control.joint_target_kd, &bad), body_f(in.body_f, &bad);
  for (int i = 0; i < count; ++i) {
    const int a = arts[i];
    for (RunScan* dof : {&ke, &kd}) dof->add(art_[a].qd_begin(), art_[a].dof_count());
    for (int k = art_body_start_[a]; k < art_body_start_[a + 1]; ++k)
      body_f.add(6 * art_body_runs_[2 * k], 6 * art_body_runs_[2 * k + 1]);
  }
  local.drives = ke.flush() | kd.flush();
  local.wrenches = body_f.flush();
  if (!finite) return;
  RunScan q(in.joint_q, &bad), qd(in.joint_qd, &bad), f(control.joint_f, &bad), ctrl(control.actuator_ctrl, &bad),
      pos(control.joint_target_pos, &bad), vel(control.joint_target_vel, &bad);
  for (int i = 0; i < count; ++i) {
    const ArticulationView& art = art_[arts[i]];
    q.add(art.q_begin(), art.coord_count());
    for (RunScan* dof : {&qd, &f}) dof->add(art.qd_begin(), art.dof_count());
    if (local.drives)  // the targets, read only where a gain is nonzero
      for (RunScan* dof : {&pos, &vel}) dof->add(art.qd_begin(), art.dof_count());
    for (int k = art_actuator_start_[arts[i]]; k < art_actuator_start_[arts[i] + 1]; ++k)
      ctrl.add(art_actuator_runs_[2 * k], art_actuator_runs_[2 * k + 1]);
  }
  for (RunScan* x : {&q, &qd, &f, &ctrl, &pos, &vel}) x->flush();
  *finite = bad == 0;
}

void SolverFeatherstone::block_unit_notes(int u, int run_end, UnitNotes& notes, StepContext& local) const {
  if (u < notes.begin || u >= notes.end) {
    notes.begin = u;
    notes.end = std::min(run_end, u + UnitNotes::kUnits);
    for (int v = u; v < notes.end; ++v) {
      int arts[kMostUnitArticulations];
      StepContext scanned = local;
      scan_unit(arts, batches_->unit_articulations(v, arts), scanned, nullptr);
      notes.drives[v - u] = scanned.drives;
      notes.wrenches[v - u] = scanned.wrenches;
    }
  }
  local.drives = notes.drives[u - notes.begin];
  local.wrenches = notes.wrenches[u - notes.begin];
}

bool SolverFeatherstone::input_finite(int a, const StepContext& step) const {
  StepContext local = step;
  bool finite = true;
  scan_unit(&a, 1, local, &finite);
  return finite;
}

void SolverFeatherstone::raise_bad_input(const StepContext& step) {
  factor_kept_ = false;  // (a non-finite input may have left its lanes of the factor non-finite)
  bool wrenches, drives;
  check_finite_step(*step.in, *step.control, &wrenches, &drives);  // throws naming the first non-finite entry
  fail("a step input is not finite");                              // (not reached)
}

void SolverFeatherstone::actuate(const Control& control, StepContext& step) {
  step.tau = control.joint_f.data();
  if (model_.actuator_count == 0 && model_.tendon_count == 0) return;
  step.tau = data_.tau.data();
}

Scalar SolverFeatherstone::tendon_force(int t, const State& in, const Control& control) const {
  // its spring's, damper's and actuators' (engine/parts/tendon.h, engine/parts/actuator.h)
  const Scalar length = tendon_length(model_, t, in.joint_q.data());
  const Scalar velocity = tendon_velocity(model_, t, in.joint_qd.data());
  Scalar force = tendon_passive_force(model_, t, length, velocity);
  for (int k = tendon_actuator_start_[t]; k < tendon_actuator_start_[t + 1]; ++k) {
    const int u = tendon_actuators_[k];
    force += actuator_joint_force(model_, u, control.actuator_ctrl[u], length, velocity);
  }
  return force;
}

void SolverFeatherstone::actuate_unit(const int* arts, int count, StepContext& local) {
  if (model_.actuator_count == 0 && model_.tendon_count == 0) return;
  const State& in = *local.in;
  const Control& control = *local.control;
  // the force along each tendon of these articulations, then each dof's joint force with its actuators' and its
  // tendons', in order; noting whether an actuator has a position or velocity term (taken implicitly)
  bool affine = false;
  for (int i = 0; i < count; ++i) {
    const int a = arts[i];
    for (int k = art_tendon_start_[a]; k < art_tendon_start_[a + 1]; ++k)
      data_.tendon_force[art_tendons_[k]] = tendon_force(art_tendons_[k], in, control);
    const ArticulationView& art = art_[a];
    for (int d = art.qd_begin(); d < art.qd_begin() + art.dof_count(); ++d) {
      Scalar sum = control.joint_f[d], stiffness = 0, damping = 0;
      for (int k = dof_actuator_start_[d]; k < dof_actuator_start_[d + 1]; ++k) {
        const DofActuator& u = dof_actuators_[k];
        const ActuatorForce f =
            actuator_force(actuator_params_[u.params], control.actuator_ctrl[u.u], in.joint_q[u.q], in.joint_qd[d]);
        sum += f.force;
        stiffness += f.stiffness;
        damping += f.damping;
      }
      for (int k = dof_entry_start_[d]; k < dof_entry_start_[d + 1]; ++k) {
        const int e = dof_entries_[k];
        sum += model_.tendon_coef[e] * data_.tendon_force[entry_tendon_[e]];
      }
      data_.tau[d] = sum;
      data_.actuator_stiffness[d] = stiffness;
      data_.actuator_damping[d] = damping;
      affine |= stiffness != 0 || damping != 0;
    }
  }
  local.actuator_stiffness = affine ? data_.actuator_stiffness.data() : nullptr;
  local.actuator_damping = affine ? data_.actuator_damping.data() : nullptr;
}

void SolverFeatherstone::guard(const StepContext& step) {
  // an articulation whose state went non-finite or beyond divergence_speed: where some input it read was not
  // finite, it is left as it was (the pass wrote none of it) and the step raises naming the first such entry,
  // after the others; else it is raised, kept as it was (Flag: the input state is finite) or reset to the
  // model's initial state at rest (Reset). No unit marked the step's trouble: none did
  if (!trouble_) {
    lap(stage_seconds_.integrate);
    return;
  }
  bool bad_input = false;
  for (int a = 0; a < model_.articulation_count && !bad_input; ++a)
    bad_input = (data_.diverged[a] || data_.factor_failure[a] >= 0) && !input_finite(a, step);
  if (bad_input && settings.on_divergence == DivergencePolicy::Raise) raise_bad_input(step);
  for (int a = 0; a < model_.articulation_count; ++a) {
    if (!data_.diverged[a] || (bad_input && !input_finite(a, step))) continue;
    if (settings.on_divergence == DivergencePolicy::Raise)
      fail("step diverged in articulation ", a, " (a non-finite state or a speed beyond ", settings.divergence_speed,
           "; dt ", step.dt, " too large for the model's stiffness or forces?)");
    const ArticulationView& art = art_[a];
    const bool keep = settings.on_divergence == DivergencePolicy::Flag;
    for (int k = art.q_begin(); k < art.q_begin() + art.coord_count(); ++k)
      data_.q_next[k] = keep ? step.in->joint_q[k] : model_.joint_q0[k];
    for (int k = art.qd_begin(); k < art.qd_begin() + art.dof_count(); ++k)
      data_.qd[k] = keep ? step.in->joint_qd[k] : 0;
    data_.pgs_converged[a] = 0;  // its next rows start from warmstarting_factor of the impulses this step left
    dense_->store(a, step);
  }
  if (bad_input) raise_bad_input(step);
  lap(stage_seconds_.integrate);
}

void SolverFeatherstone::check_factors(const StepContext& step) const {
  // (a factor that failed on a non-finite input is the guard's to raise, after the other worlds' step)
  if (!trouble_) return;
  for (int a = 0; a < model_.articulation_count; ++a)
    if (data_.factor_failure[a] >= 0 && input_finite(a, step))
      fail("articulation ", a, ": mass matrix is not positive definite at dof ", data_.factor_failure[a],
           " (a massless link without children?)");
}

}  // namespace novaphy
