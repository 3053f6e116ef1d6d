// The dense route: one articulation a unit, on the scalar kernels in double (kernels/fk, rnea, crba,
// cholesky, aba, integrate). It steps what the blocks do not: articulations of aba_min_dofs dofs or
// more (ABA's O(n) factor), every articulation while coriolis_implicitness > 0 (an LU of M + theta dt C)
// or use_batch_kernels is off, and those without dofs (their bodies' poses). Its rows are the islands'
// (engine/solver/islands/rows.h); the drives, the guard and the wrenches are the parts the blocks use.
#pragma once

#include <Eigen/LU>
#include <cstdint>
#include <vector>

#include "engine/solver/blocks/blocks.h"

namespace novaphy {

class DenseArticulations final : public StepRoute {
 public:
  // `model` the model's own arrays, `art` the views the kernels see (the welded model), `welded[a]`
  // articulation a's welded bodies
  DenseArticulations(const Model& model, const std::vector<ArticulationView>& art,
                     const std::vector<std::vector<WeldedBody>>& welded);

  // the articulations it steps from now on, a unit each; their factors are made afresh
  void assign(const std::vector<int>& articulations);
  const std::vector<int>& articulations() const { return units_; }

  int unit_count() const override { return static_cast<int>(units_.size()); }
  int unit_articulations(int unit, int* out) const override {
    out[0] = units_[unit];
    return 1;
  }
  void begin_step(const StepContext&) override {}
  void end_step(const StepContext&) override {}
  void dynamics(const UnitPass& pass, const StepContext& step, const UnitInputs& inputs) override;
  void rows(const UnitPass&, const StepContext&) override {}  // (the islands')
  void integrate(const UnitPass& pass, const StepContext& step) override;
  // the articulation's state, unless it diverged or its factor failed
  void store(const UnitPass& pass, const StepContext& step) override;
  // out.joint_q, joint_qd from step.q_next and step.qd, and body_q, body_qd from them by the scalar
  // kinematics, for any articulation (the guard's kept and reset ones too)
  void write_state(int a, const StepContext& step);

  void solve_mass(int a, Scalar* x) override;
  void point_jacobian(int a, int link, const Vec3* p, const Vec3& d, Scalar sign, Scalar* J) const override;
  std::size_t bytes() const override;

 private:
  enum class Factor : std::uint8_t { None, Cholesky, Aba };
  ArticulationScratch& scratch(int a);
  // rhs = tau - bias + the implicit dampers, springs and drives; diagonal = what they add to H
  void joint_forces(int a, const StepContext& step, const UnitInputs& inputs, Scalar* rhs, VecX& diagonal);
  // rhs = M^-1 rhs, M factored as this step needs; returns the dof whose pivot failed, or -1
  int factor_and_solve(int a, const StepContext& step, Scalar* rhs);
  // applied wrenches of articulation a's bodies gathered onto its links (welded bodies' onto theirs)
  const Scalar* link_wrenches(int a, const Scalar* body_f);

  const Model& model_;
  const std::vector<ArticulationView>& art_;
  const std::vector<std::vector<WeldedBody>>& welded_;
  std::vector<int> units_;
  // per articulation
  std::vector<ArticulationScratch> scratch_;            // sized on first use
  std::vector<Factor> factor_;                          // what its factor in scratch is
  std::vector<std::uint8_t> constant_mass_;             // 1 for Prismatic and Fixed joints only: H is computed once
  std::vector<MatX> constant_H_;                        // its H once computed, where constant
  std::vector<VecX> factored_diagonal_;                 // the implicit diagonal in its factor
  std::vector<Eigen::PartialPivLU<MatX>> implicit_lu_;  // M + theta dt C (coriolis_implicitness)
  std::vector<std::vector<int>> rotational_;            // its dofs angular damping scales (local)
  std::vector<Scalar> rhs_;                             // [dof]
  std::vector<Scalar> link_f_;                          // [body][6] link_wrenches' output
};

}  // namespace novaphy
