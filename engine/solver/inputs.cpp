// SolverFeatherstone, what a step reads: its arguments checked, each unit's notes of wrenches and drives, the
// joint forces of actuators and tendons, and a world whose output went wrong traced to a non-finite input
// (docs/errors.md). The rest of the solver: solver_featherstone.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include "engine/model/actuator.h"
#include "engine/model/error.h"
#include "engine/model/finite_checks.h"
#include "engine/model/tendon.h"
#include "engine/solver/solver_featherstone.h"
#include "engine/solver/step_arguments.h"

namespace novaphy {

void SolverFeatherstone::check_step(const State& in, const State& out, const Control& control, const Contacts& contacts,
                                    Scalar dt) {
  if (!(dt > 0) || !std::isfinite(dt)) fail("dt must be finite and > 0, got ", dt);
  settings.check();
  check_step_arguments(model_, in, out, control, contacts, dt);
  bool loose_finite = true;
  for (const int b : built_.loose_bodies)
    for (int k = 0; k < 6; ++k) loose_finite &= std::isfinite(in.body_f[6 * static_cast<size_t>(b) + k]);
  for (const int u : built_.loose_actuators) loose_finite &= std::isfinite(control.actuator_ctrl[u]);
  if (loose_finite) return;
  bool wrenches, drives;
  check_finite_step(in, control, &wrenches, &drives);  // throws naming the first non-finite entry
}

namespace {

// the entries of one array a unit reads, in ranges joined where one starts as the last ended (a block's worlds
// lie one after another), scanned a run at a time (scan_bits, as check_finite_step's); with `negative`, noting
// whether an entry is below 0 (a PD gain)
class RunScan {
 public:
  RunScan(const std::vector<Scalar>& x, std::uint64_t* bad, bool* negative = nullptr)
      : x_(x), bad_(bad), negative_(negative) {}
  void add(int begin, int count) {
    if (begin != end_) flush();
    if (begin != end_) begin_ = begin;
    end_ = begin + count;
  }
  // scans what is pending; returns whether any entry scanned so far is nonzero
  bool flush() {
    scan_bits(x_.data(), begin_, end_, bad_, &nonzero_);
    if (negative_) {
      bool below = false;
      for (int k = begin_; k < end_; ++k) below |= x_[k] < 0;
      *negative_ |= below;
    }
    begin_ = end_;
    return nonzero_ != 0;
  }

 private:
  const std::vector<Scalar>& x_;
  std::uint64_t* bad_;
  bool* negative_;
  std::uint64_t nonzero_ = 0;
  int begin_ = 0, end_ = 0;
};

}  // namespace

bool SolverFeatherstone::scan_unit(const int* arts, int count, const StepContext& step, UnitInputs& inputs,
                                   bool* valid) const {
  const State& in = *step.in;
  const Control& control = *step.control;
  std::uint64_t bad = 0;
  bool negative = false;
  // the notes: the gains and wrenches, and the actuators' commands (their control range would clamp an infinite one
  // to a finite force: scanned here, not found from the output)
  RunScan ke(control.joint_target_ke, &bad, &negative), kd(control.joint_target_kd, &bad, &negative),
      body_f(in.body_f, &bad), ctrl(control.actuator_ctrl, &bad);
  for (int i = 0; i < count; ++i) {
    const int a = arts[i];
    for (RunScan* dof : {&ke, &kd}) dof->add(built_.art[a].qd_begin(), built_.art[a].dof_count());
    for (int k = built_.art_body_start[a]; k < built_.art_body_start[a + 1]; ++k)
      body_f.add(6 * built_.art_body_runs[2 * k], 6 * built_.art_body_runs[2 * k + 1]);
    for (int k = built_.art_actuator_start[a]; k < built_.art_actuator_start[a + 1]; ++k)
      ctrl.add(built_.art_actuator_runs[2 * k], built_.art_actuator_runs[2 * k + 1]);
  }
  inputs.drives = ke.flush() | kd.flush();
  inputs.wrenches = body_f.flush() || model_wrenches_.any();
  ctrl.flush();
  const bool invalid = bad != 0 || negative;
  if (!valid) return invalid;
  RunScan q(in.joint_q, &bad), qd(in.joint_qd, &bad), f(control.joint_f, &bad), pos(control.joint_target_pos, &bad),
      vel(control.joint_target_vel, &bad);
  for (int i = 0; i < count; ++i) {
    const ArticulationView& art = built_.art[arts[i]];
    q.add(art.q_begin(), art.coord_count());
    for (RunScan* dof : {&qd, &f}) dof->add(art.qd_begin(), art.dof_count());
    if (inputs.drives)  // the targets, read only where a gain is nonzero
      for (RunScan* dof : {&pos, &vel}) dof->add(art.qd_begin(), art.dof_count());
  }
  for (RunScan* x : {&q, &qd, &f, &pos, &vel}) x->flush();
  *valid = bad == 0 && !negative;
  return invalid;
}

bool SolverFeatherstone::block_unit_notes(int u, int run_end, const StepContext& step, UnitNotes& notes,
                                          UnitInputs& inputs) const {
  if (u < notes.begin || u >= notes.end) {
    notes.begin = u;
    notes.end = std::min(run_end, u + UnitNotes::kUnits);
    for (int v = u; v < notes.end; ++v) {
      int arts[kMostUnitArticulations];
      UnitInputs scanned;
      notes.invalid[v - u] = scan_unit(arts, batches_->unit_articulations(v, arts), step, scanned, nullptr);
      notes.drives[v - u] = scanned.drives;
      notes.wrenches[v - u] = scanned.wrenches;
    }
  }
  inputs.drives = notes.drives[u - notes.begin];
  inputs.wrenches = notes.wrenches[u - notes.begin];
  return notes.invalid[u - notes.begin];
}

bool SolverFeatherstone::input_valid(int a, const StepContext& step) const {
  UnitInputs inputs;
  bool valid = true;
  scan_unit(&a, 1, step, inputs, &valid);
  return valid;
}

void SolverFeatherstone::raise_bad_input(const StepContext& step) {
  factor_kept_ = false;  // (a bad input may have left its lanes of the factor non-finite)
  const State& in = *step.in;
  const Control& control = *step.control;
  // the world of an entry: of its articulation, found from its dof, coordinate, body or actuator
  auto coord_world = [&](int k) {
    int a = 0;
    while (built_.art[a].q_begin() + built_.art[a].coord_count() <= k) ++a;
    return model_.articulation_world(a);
  };
  auto dof_world = [&](int k) { return model_.articulation_world(built_.index.dof_articulation[k]); };
  auto body_world = [&](int k) { return model_.body_world[k / 6]; };
  auto actuator_world = [&](int u) {
    const int joint = model_.actuator_joint[u], tendon = model_.actuator_tendon[u], body = model_.actuator_body[u];
    if (body >= 0) return model_.body_world[body];
    if (joint >= 0) return dof_world(model_.joint_qd_start[joint]);
    if (tendon < 0 || built_.tendon_articulation[tendon] < 0) return -1;  // (on nothing: check_step checked it)
    return model_.articulation_world(built_.tendon_articulation[tendon]);
  };
  bool drives = false;
  for (const Scalar* gains : {control.joint_target_ke.data(), control.joint_target_kd.data()})
    for (int k = 0; k < model_.joint_dof_count; ++k) drives |= gains[k] != 0;
  // the arrays in check_finite_step's order (the PD targets only where a gain reads them), then the gains' signs
  struct Read {
    const std::vector<Scalar>& x;
    const char* name;
    std::function<int(int)> world;
  };
  const Read reads[] = {{in.joint_q, "joint_q", coord_world},
                        {in.joint_qd, "joint_qd", dof_world},
                        {in.body_f, "body_f", body_world},
                        {control.joint_f, "joint_f", dof_world},
                        {control.actuator_ctrl, "actuator_ctrl", actuator_world},
                        {control.joint_target_pos, "joint_target_pos", dof_world},
                        {control.joint_target_vel, "joint_target_vel", dof_world},
                        {control.joint_target_ke, "joint_target_ke", dof_world},
                        {control.joint_target_kd, "joint_target_kd", dof_world}};
  for (const Read& r : reads) {
    const bool target = &r.x == &control.joint_target_pos || &r.x == &control.joint_target_vel;
    if (target && !drives) continue;
    for (size_t k = 0; k < r.x.size(); ++k)
      if (!std::isfinite(r.x[k]))
        fail(r.name, "[", k, "] is not finite: ", r.x[k], " (world ", r.world(static_cast<int>(k)), ")");
  }
  for (const Read& r : {reads[7], reads[8]})
    for (size_t k = 0; k < r.x.size(); ++k)
      if (r.x[k] < 0)
        fail(r.name, "[", k, "] must be >= 0 (as the builder's gains), got ", r.x[k], " (world ",
             r.world(static_cast<int>(k)), ")");
  fail("a step input is not valid");  // (not reached)
}

Scalar SolverFeatherstone::deepest_contact(int a, const Contacts& contacts) const {
  Scalar deepest = 0;
  for (int c = 0; c < contacts.contact_count; ++c)
    if (built_.index.moving(contacts.contact_body_a[c]) == a || built_.index.moving(contacts.contact_body_b[c]) == a)
      deepest = std::max(deepest, contacts.contact_depth[c]);
  return deepest;
}

void SolverFeatherstone::actuate(const Control& control, StepContext& step) {
  step.tau = control.joint_f.data();
  if (model_.actuator_count == 0 && model_.tendon_count == 0) return;
  step.tau = data_.tau.data();
}

Scalar SolverFeatherstone::tendon_force(int t, const State& in, const Control& control) const {
  // its spring's, damper's and actuators' (engine/model/tendon.h, engine/model/actuator.h)
  const Scalar length = tendon_length(model_, t, in.joint_q.data());
  const Scalar velocity = tendon_velocity(model_, t, in.joint_qd.data());
  Scalar force = tendon_passive_force(model_, t, length, velocity);
  for (int k = built_.tendon_actuator_start[t]; k < built_.tendon_actuator_start[t + 1]; ++k) {
    const int u = built_.tendon_actuators[k];
    force += actuator_joint_force(model_, u, control.actuator_ctrl[u], length, velocity);
  }
  return force;
}

void SolverFeatherstone::actuate_unit(const int* arts, int count, const StepContext& step, UnitInputs& inputs) {
  if (model_.actuator_count == 0 && model_.tendon_count == 0) return;
  const State& in = *step.in;
  const Control& control = *step.control;
  // the force along each tendon of these articulations, then each dof's joint force with its actuators' and its
  // tendons', in order; noting whether an actuator has a position or velocity term (taken implicitly)
  bool affine = false;
  for (int i = 0; i < count; ++i) {
    const int a = arts[i];
    for (int k = built_.art_tendon_start[a]; k < built_.art_tendon_start[a + 1]; ++k)
      data_.tendon_force[built_.art_tendons[k]] = tendon_force(built_.art_tendons[k], in, control);
    const ArticulationView& art = built_.art[a];
    for (int d = art.qd_begin(); d < art.qd_begin() + art.dof_count(); ++d) {
      Scalar sum = control.joint_f[d], stiffness = 0, damping = 0;
      for (int k = built_.dof_actuator_start[d]; k < built_.dof_actuator_start[d + 1]; ++k) {
        const SolverModel::DofActuator& u = built_.dof_actuators[k];
        const ActuatorForce f = actuator_force(built_.actuator_params[u.params], control.actuator_ctrl[u.u],
                                               in.joint_q[u.q], in.joint_qd[d]);
        sum += f.force;
        stiffness += f.stiffness;
        damping += f.damping;
      }
      for (int k = built_.dof_entry_start[d]; k < built_.dof_entry_start[d + 1]; ++k) {
        const int e = built_.dof_entries[k];
        sum += model_.tendon_coef[e] * data_.tendon_force[built_.entry_tendon[e]];
      }
      data_.tau[d] = sum;
      data_.actuator_stiffness[d] = stiffness;
      data_.actuator_damping[d] = damping;
      affine |= stiffness != 0 || damping != 0;
    }
  }
  inputs.actuator_stiffness = affine ? data_.actuator_stiffness.data() : nullptr;
  inputs.actuator_damping = affine ? data_.actuator_damping.data() : nullptr;
}

void SolverFeatherstone::guard(const StepContext& step) {
  // an articulation that diverged (engine/solver/parts/guard.h, or flagged: a contact too deep, a bad input): where
  // some input it read was not finite or a PD gain negative, it is left as it was (the pass wrote none of it) and the
  // step raises naming the first such entry, after the others; else it is raised, kept as it was (Flag: the input
  // state is finite) or reset to the reset state (Reset). No unit marked the step's trouble: none did
  if (!trouble_) {
    lap(stage_seconds_.integrate);
    return;
  }
  bool bad_input = false;
  for (int a = 0; a < model_.articulation_count && !bad_input; ++a)
    bad_input = (data_.diverged[a] || data_.factor_failure[a] >= 0) && !input_valid(a, step);
  if (bad_input && settings.on_divergence == DivergencePolicy::Raise) raise_bad_input(step);
  for (int a = 0; a < model_.articulation_count; ++a) {
    if (!data_.diverged[a] || (bad_input && !input_valid(a, step))) continue;
    if (settings.on_divergence == DivergencePolicy::Raise) {
      const Scalar depth = deepest_contact(a, *step.contacts);
      if (depth > settings.divergence_depth)
        fail("step diverged in articulation ", a, ": a contact ", depth, " m deep, beyond divergence_depth ",
             settings.divergence_depth, " m (the last step's dt too large for the scene?)");
      fail("step diverged in articulation ", a, " (a non-finite state, a speed beyond ", settings.divergence_speed,
           " or a kinetic energy beyond ", settings.divergence_energy, " J/kg; dt ", step.dt,
           " too large for the model's stiffness or forces?)");
    }
    const ArticulationView& art = built_.art[a];
    const bool keep = settings.on_divergence == DivergencePolicy::Flag;
    for (int k = art.q_begin(); k < art.q_begin() + art.coord_count(); ++k)
      data_.q_next[k] = keep ? step.in->joint_q[k] : reset_q_[k];
    for (int k = art.qd_begin(); k < art.qd_begin() + art.dof_count(); ++k)
      data_.qd[k] = keep ? step.in->joint_qd[k] : reset_qd_[k];
    data_.pgs_converged[a] = 0;  // its next rows start from warmstarting_factor of the impulses this step left
    dense_->write_state(a, step);
  }
  if (bad_input) raise_bad_input(step);
  lap(stage_seconds_.integrate);
}

void SolverFeatherstone::check_factors(const StepContext& step) const {
  // (a factor that failed on a non-finite input is the guard's to raise, after the other worlds' step)
  if (!trouble_) return;
  for (int a = 0; a < model_.articulation_count; ++a)
    if (data_.factor_failure[a] >= 0 && input_valid(a, step))
      fail("articulation ", a, ": mass matrix is not positive definite at dof ", data_.factor_failure[a],
           " (a massless link without children?)");
}

}  // namespace novaphy
