// The blocks route: articulations that share joints, frames and axes (every world of a replicated
// robot) are grouped, kLanes<T> worlds to a block, and stepped by the batched kernels (kernels/batch.h)
// in the model's precision, a block per unit. Per-world parameters (masses, inertias, armature, damping,
// springs, limits; gains and targets from the Control) stay per lane, so a randomised batch keeps the
// blocks. Each thread owns its scratch, and a step allocates nothing.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/solver/route.h"

namespace novaphy {

// a body welded into a link by a Fixed joint (engine/model/weld.h): where its state comes from
struct WeldedBody {
  int body = 0;
  int link = 0;
  Transform offset;  // its pose in the link's frame
};

class ArticulationBatches : public StepRoute {
 public:
  // batches over the articulations a with batched[a] != 0, in precision `precision`; `model` holds the
  // arrays the views `art` point into (the welded model), `welded[a]` articulation a's welded bodies,
  // `com` every body's own centre of mass and `limit_slot[dof]` the solver's number for that dof's limit
  // (-1: a dof without a finite limit)
  static std::unique_ptr<ArticulationBatches> make(const Model& model, const std::vector<ArticulationView>& art,
                                                   const std::vector<std::uint8_t>& batched,
                                                   const std::vector<std::vector<WeldedBody>>& welded,
                                                   const std::vector<Scalar>& com, const std::vector<int>& limit_slot,
                                                   Precision precision);

  // batches of fewer than `max_dofs` dofs on, the others off (their articulations take the dense route;
  // a batch switched off refactors when it is next on); the units are the blocks of the batches on
  virtual void enable(int max_dofs) = 0;
  // the parameters of the articulations a with changed[a] != 0 read again (Model::set_parameter): from `model`
  // (the arrays the views point into) and `com` as make() read them, the blocks on `threads` threads
  virtual void read_parameters(const Model& model, const std::vector<Scalar>& com,
                               const std::vector<std::uint8_t>& changed, int threads) = 0;
  // true when articulation a is in a batch that is on
  virtual bool active(int a) const = 0;
  // where the blocks keep the limit impulses of their articulations in the step's limit_impulse: cell
  // [2 * slot + side] for the limit slots given to make() (side 0 the lower limit, 1 the upper), -1 for the
  // others. They take cells [0, limit_cell_count()), a block's laid out [limited dof][side][lane]
  virtual const std::vector<int>& limit_cells() const = 0;
  virtual int limit_cell_count() const = 0;
  // forward dynamics: qdd = M^-1 (tau - bias) with M = H + armature, in the blocks' precision, for every
  // batched articulation (dt = 0, no drives, no angular damping) under the wrenches body_f [6 body] (applied
  // where `wrenches`); factor_failure[a] = the dof whose pivot failed, or left alone
  virtual void accelerations(const State& in, const Control& control, const Scalar* tau, const Scalar* body_f,
                             bool wrenches, Scalar* qdd, int* factor_failure) = 0;
  // the rows stage's phases summed over the threads since the step began (settings.profile_stages)
  virtual RowPhaseSeconds row_phases() const = 0;

  virtual int group_count() const = 0;
  virtual int block_count() const = 0;
  virtual int lanes() const = 0;
};

}  // namespace novaphy
