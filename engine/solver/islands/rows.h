// The rows the blocks do not solve: those of the dense route's articulations, and every row of an
// articulation a contact joins to another moving one this step. A row acts on the dofs of one or two
// articulations through J and M^-1 J^T, each side's from the route that steps it; the contact and limit
// rows are the parts of engine/solver/parts/rows.h, as are the rows of equality constraints and tendons,
// which the islands build for either route. Articulations joined by rows form islands, each swept by
// kernels/pgs on one thread, the islands in parallel (the same bits as one sweep over all rows).
#pragma once

#include <vector>

#include "engine/model/spatial_tendon.h"
#include "engine/solver/parts/soft_row.h"
#include "engine/solver/route.h"
#include "kernels/pgs.h"

namespace novaphy {

class IslandRows {
 public:
  // limited_joints: the Revolute and Prismatic joints with a finite limit, by articulation (a's from
  // limited_start[a]); limit_cell[2 m + side]: where limited joint m's side keeps its impulse
  IslandRows(const Model& model, const std::vector<ArticulationView>& art, const ArticulationIndex& index,
             const std::vector<int>& limited_joints, const std::vector<int>& limited_start,
             const std::vector<int>& limit_cell);

  // this step's rows afresh; route[a]: the route stepping articulation a
  void begin(const std::vector<StepRoute*>& route);
  // the limit rows and then the friction-loss rows of `articulations`, then the rows of `contacts`
  void add_limit_rows(const StepContext& step, const std::vector<int>& articulations);
  void add_friction_rows(const StepContext& step, const std::vector<int>& articulations);
  void add_contact_rows(const StepContext& step, const std::vector<int>& contacts);
  // the rows of the model's equality constraints and of its tendons that would cross a limit
  void add_constraint_rows(const StepContext& step);
  // the islands swept on `threads` threads; the impulses kept (contacts in contact_impulse, limits in
  // step.limit_impulse for `articulations`)
  void solve(const StepContext& step, const std::vector<int>& articulations, const std::vector<int>& contacts,
             int threads);
  std::size_t bytes() const;

 private:
  // a row over the dofs of up to two articulations (-1: none), J zeroed
  int begin_row(int art_a, int art_b, RowKind kind, Scalar target);
  // the last row begun taken back, its pool with it
  void drop_last_row();
  Scalar* row_jacobian(int row, int art);
  // a contact-type row: relative velocity of body b's point p minus body a's along d (-1: the world), or with
  // p null their relative angular velocity
  int add_row(int body_a, int body_b, const Vec3* p, const Vec3& d, RowKind kind);
  // the share of the last step's impulses row r (not a contact's: ContactRows::warm_share) starts from: warm_share
  // over the articulations it acts on (all of them converged, or not)
  Scalar warm_share_of(int row, const StepContext& step) const;
  // row r soft (its cfm and target; soft_row.h)
  void soften(int r, const SoftRow& soft);
  // M^-1 J^T and the effective mass, once J is filled in
  void finish_row(int row, Scalar cfm);
  void group_islands();

  const Model& model_;
  const std::vector<ArticulationView>& art_;
  const ArticulationIndex& index_;
  const std::vector<int>& limited_joints_;
  const std::vector<int>& limited_start_;
  const std::vector<int>& limit_cell_;
  const std::vector<StepRoute*>* route_ = nullptr;
  std::vector<PgsRow> rows_;
  int row_count_ = 0;
  std::vector<Scalar> J_, MinvJT_;  // the rows' pools
  int pool_size_ = 0;
  std::vector<int> limit_row_;     // [dof][2] the row of each active limit, -1
  std::vector<int> friction_row_;  // [dof] its friction-loss row, -1
  std::vector<int> contact_row_;   // [contact] the first row of each contact added
  std::vector<int> contact_dims_;  // [contact] its rows: 3, or 4 or 6 with the torsional and rolling ones
  std::vector<int> equality_row_;  // [equality] its first row, -1
  std::vector<int> tendon_row_;    // [tendon][3] the row of each active limit and of its dry friction, -1
  // the rows of equality e (connect or weld, joint coupling), of a tendon's limits and dry friction, and their
  // impulses kept
  void add_body_rows(const StepContext& step, int e);
  void add_coupling_row(const StepContext& step, int e);
  void add_tendon_rows(const StepContext& step, int t);
  // J of row r += sign * tendon t's length's Jacobian (a spatial tendon's from spans_)
  void tendon_jacobian(int r, int t, Scalar sign);
  std::vector<TendonSpan> spans_;  // the spatial tendon whose rows are being added: its pieces
  void keep_constraint_impulses(const StepContext& step) const;
  // islands (articulations joined by rows, named by their lowest articulation): island i's rows are
  // island_rows_[island_start_[i] .. island_start_[i + 1])
  std::vector<int> island_parent_, island_of_row_, island_start_, island_rows_, fill_;
};

}  // namespace novaphy
