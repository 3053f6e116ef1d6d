#include "engine/solver/islands/rows.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "engine/model/spatial_tendon.h"
#include "engine/model/tendon.h"
#include "engine/solver/parts/rows.h"
#include "engine/threads/parallel.h"

namespace novaphy {

IslandRows::IslandRows(const Model& model, const std::vector<ArticulationView>& art, const ArticulationIndex& index,
                       const std::vector<int>& limited_joints, const std::vector<int>& limited_start,
                       const std::vector<int>& limit_cell)
    : model_(model),
      art_(art),
      index_(index),
      limited_joints_(limited_joints),
      limited_start_(limited_start),
      limit_cell_(limit_cell) {
  limit_row_.assign(2 * static_cast<size_t>(model.joint_dof_count), -1);
  friction_row_.assign(model.joint_dof_count, -1);
  equality_row_.assign(model.equality_count, -1);
  tendon_row_.assign(3 * static_cast<size_t>(model.tendon_count), -1);
}

void IslandRows::begin(const std::vector<StepRoute*>& route) {
  route_ = &route;
  row_count_ = 0;
  pool_size_ = 0;
}

int IslandRows::begin_row(int art_a, int art_b, RowKind kind, Scalar target) {
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

void IslandRows::drop_last_row() {
  --row_count_;
  if (rows_[row_count_].side_count > 0) pool_size_ = rows_[row_count_].pool[0];
}

Scalar* IslandRows::row_jacobian(int r, int art) {
  PgsRow& row = rows_[r];
  for (int s = 0; s < row.side_count; ++s)
    if (row.dof_begin[s] == art_[art].qd_begin()) return J_.data() + row.pool[s];
  return nullptr;
}

int IslandRows::add_row(int body_a, int body_b, const Vec3* p, const Vec3& d, RowKind kind) {
  const int art_a = index_.moving(body_a), art_b = index_.moving(body_b);
  const int r = begin_row(art_a, art_b, kind, 0);
  if (art_b >= 0) (*route_)[art_b]->point_jacobian(art_b, index_.body_link[body_b], p, d, 1, row_jacobian(r, art_b));
  if (art_a >= 0) (*route_)[art_a]->point_jacobian(art_a, index_.body_link[body_a], p, d, -1, row_jacobian(r, art_a));
  return r;
}

Scalar IslandRows::warm_share_of(int r, const StepContext& step) const {
  bool converged = true;
  for (int s = 0; s < rows_[r].side_count; ++s)
    converged = converged && step.pgs_converged[index_.dof_articulation[rows_[r].dof_begin[s]]] != 0;
  return warm_share<Scalar>(converged, step.settings);
}

void IslandRows::finish_row(int r, Scalar cfm) {
  PgsRow& row = rows_[r];
  Scalar W = 0;
  for (int s = 0; s < row.side_count; ++s) {
    Scalar* z = MinvJT_.data() + row.pool[s];
    const Scalar* J = J_.data() + row.pool[s];
    std::copy(J, J + row.dof_count[s], z);
    const int a = index_.dof_articulation[row.dof_begin[s]];
    (*route_)[a]->solve_mass(a, z);
    for (int k = 0; k < row.dof_count[s]; ++k) W += J[k] * z[k];
  }
  row.inv_mass = row_inv_mass(W, cfm + row.cfm);
}

void IslandRows::add_limit_rows(const StepContext& step, const std::vector<int>& articulations) {
  const Scalar dt = step.dt;
  for (const int a : articulations)
    for (int m = limited_start_[a]; m < limited_start_[a + 1]; ++m) {
      const int j = limited_joints_[m], g = model_.joint_qd_start[j];
      const Scalar q = step.in->joint_q[model_.joint_q_start[j]];
      for (int side = 0; side < 2; ++side) {
        limit_row_[2 * g + side] = -1;
        const Scalar limit = side == 0 ? model_.joint_limit_lower[g] : model_.joint_limit_upper[g];
        const Scalar gap = LimitRow::gap(q, limit, side);
        const Softness soft = softness_of(&model_.joint_limit_solref[2 * g], &model_.joint_limit_solimp[5 * g],
                                          model_.joint_invweight0[g]);
        const bool softened = step.settings.soft_constraints && soft.soft();
        if (!LimitRow::on(limit, gap, step.qd[g], side, dt, softened)) continue;
        const int r = begin_row(a, -1, LimitRow::kKind, LimitRow::target(gap, step.settings, dt));
        row_jacobian(r, a)[g - art_[a].qd_begin()] = LimitRow::sign(side);
        if (softened) soften(r, LimitRow::soft(gap, LimitRow::sign(side) * step.in->joint_qd[g], soft, dt));
        rows_[r].lambda = LimitRow::warm(step.limit_impulse[limit_cell_[2 * m + side]], warm_share_of(r, step));
        limit_row_[2 * g + side] = r;
      }
    }
}

void IslandRows::add_friction_rows(const StepContext& step, const std::vector<int>& articulations) {
  for (const int a : articulations)
    for (int g = art_[a].qd_begin(); g < art_[a].qd_begin() + art_[a].dof_count(); ++g) {
      friction_row_[g] = -1;
      const Scalar loss = model_.joint_frictionloss[g];
      if (!FrictionLossRow::on(loss)) continue;
      const int r = begin_row(a, -1, FrictionLossRow::kKind, 0);
      row_jacobian(r, a)[g - art_[a].qd_begin()] = 1;
      rows_[r].bound = FrictionLossRow::bound(loss, step.dt);
      const Softness soft = softness_of(&model_.joint_friction_solref[2 * g], &model_.joint_friction_solimp[5 * g],
                                        model_.joint_invweight0[g]);
      if (step.settings.soft_constraints && soft.soft())
        soften(r, FrictionLossRow::soft(step.in->joint_qd[g], soft, step.dt));
      rows_[r].lambda = FrictionLossRow::warm(step.friction_impulse[g], warm_share_of(r, step));
      friction_row_[g] = r;
    }
}

void IslandRows::add_contact_rows(const StepContext& step, const std::vector<int>& contacts) {
  const Contacts& C = *step.contacts;
  if (static_cast<int>(contact_row_.size()) < C.contact_count) {
    contact_row_.resize(C.contact_count);
    contact_dims_.resize(C.contact_count);
  }
  const Scalar* qd = step.in->joint_qd.data();
  for (const int c : contacts) {
    const int ba = C.contact_body_a[c], bb = C.contact_body_b[c];
    const Vec3 p = Eigen::Map<const Vec3>(&C.contact_point[3 * c]);
    const ContactInput<Scalar> in = ContactRows::read(C, c, *step.lists.shapes, model_.impratio);
    // condim 4: a torsional row about the normal; 6: and two rolling rows about the tangents. Their kinds those of
    // the blocks' contact rows, laid out for the model's largest condim (a cone of two rows is the blocks' cone of
    // condim 3 lanes)
    const int dims = std::min(step.lists.dims, ContactRows::count(static_cast<int>(in.condim)));
    Scalar d[9], warm[6], v[6], target[6], cfm[6], mu[6];
    contact_frame(&C.contact_normal[3 * c], d);
    ContactRows::warm(in, d, ContactRows::warm_share<Scalar>(step.settings), warm);
    const int first = row_count_;
    for (int e = 0; e < dims; ++e) {
      const Scalar* axis = ContactRows::direction(d, e);
      const int r = add_row(ba, bb, ContactRows::turns(e) ? nullptr : &p, Vec3(axis[0], axis[1], axis[2]),
                            ContactRows::kind(e, step.lists.dims));
      rows_[r].lambda = warm[e];
      if (e > 0) rows_[r].normal = first;
      v[e] = row_velocity(rows_[r], J_, qd);  // (at the step's start)
    }
    ContactRows::targets(in, v, dims, step.settings, step.dt, target, cfm, mu);
    for (int e = 0; e < dims; ++e) {
      rows_[first + e].target = target[e];
      rows_[first + e].cfm = cfm[e];
      rows_[first + e].mu = mu[e];
    }
    contact_row_[c] = first;
    contact_dims_[c] = dims;
  }
}

void IslandRows::soften(int r, const SoftRow& soft) {
  rows_[r].target = soft.target;
  rows_[r].cfm = soft.cfm;
}

void IslandRows::add_constraint_rows(const StepContext& step) {
  for (int e = 0; e < model_.equality_count; ++e) {
    if (static_cast<EqualityType>(model_.equality_type[e]) == EqualityType::JointCoupling)
      add_coupling_row(step, e);
    else
      add_body_rows(step, e);
  }
  for (int t = 0; t < model_.tendon_count; ++t) add_tendon_rows(step, t);
}

void IslandRows::add_body_rows(const StepContext& step, int e) {
  // the anchors in the world at the step's body poses; rows along x, y and z of the second's velocity less
  // the first's at their midpoint, each driving its part of the gap p2 - p1 to zero; a weld's three more of
  // their angular velocities, driving the rotation from body 2's held orientation to its own to zero
  const int b1 = model_.equality_object[2 * e], b2 = model_.equality_object[2 * e + 1];
  const auto type = static_cast<EqualityType>(model_.equality_type[e]);
  const bool weld = type == EqualityType::Weld;
  Vec3 mid, error[2] = {Vec3::Zero(), Vec3::Zero()};
  BodyEquality::of(model_, e).errors(body_pose(*step.in, b1), body_pose(*step.in, b2), &mid, &error[0],
                                     weld ? &error[1] : nullptr);
  equality_row_[e] = row_count_;
  const bool soft = step.settings.soft_constraints && is_soft(&model_.equality_solref[2 * e]);
  // a soft weld's rotation rows read MuJoCo's error (EqualityRow::soft_turn), its impedance MuJoCo's whole error
  const Vec3 turn = soft && weld ? EqualityRow::soft_turn(error[1]) : error[1];
  const Scalar whole = std::sqrt(error[0].squaredNorm() + turn.squaredNorm() / 4);
  for (int k = 0; k < EqualityRow::count(type); ++k) {
    const int r = add_row(b1, b2, k < 3 ? &mid : nullptr, Vec3::Unit(k % 3), EqualityRow::kKind);
    rows_[r].bound = EqualityRow::bound();
    rows_[r].target = EqualityRow::target(error[k / 3][k % 3], step.settings, step.dt);
    rows_[r].lambda = EqualityRow::warm(step.equality_impulse[6 * e + k], warm_share_of(r, step));
    if (soft)
      soften(r, EqualityRow::soft(k < 3 ? error[0][k] : turn[k - 3], whole,
                                  row_velocity(rows_[r], J_, step.in->joint_qd.data()),
                                  EqualityRow::softness(model_, e, k >= 3), step.dt));
  }
}

void IslandRows::add_coupling_row(const StepContext& step, int e) {
  const int j1 = model_.equality_object[2 * e], j2 = model_.equality_object[2 * e + 1];
  const int d1 = model_.joint_qd_start[j1], d2 = j2 < 0 ? -1 : model_.joint_qd_start[j2];
  const Scalar* q = step.in->joint_q.data();
  const JointCoupling coupling = JointCoupling::of(model_, e);
  Scalar slope = 0;
  const Scalar error =
      coupling.error(q[model_.joint_q_start[j1]], j2 < 0 ? coupling.q2_ref : q[model_.joint_q_start[j2]], &slope);
  const int a1 = index_.dof_articulation[d1], a2 = d2 < 0 ? -1 : index_.dof_articulation[d2];
  const int r =
      begin_row(a1, a2 == a1 ? -1 : a2, EqualityRow::kKind, EqualityRow::target(error, step.settings, step.dt));
  row_jacobian(r, a1)[d1 - art_[a1].qd_begin()] += 1;
  if (d2 >= 0) row_jacobian(r, a2)[d2 - art_[a2].qd_begin()] -= slope;
  rows_[r].bound = EqualityRow::bound();
  rows_[r].lambda = EqualityRow::warm(step.equality_impulse[6 * e], warm_share_of(r, step));
  if (step.settings.soft_constraints && is_soft(&model_.equality_solref[2 * e]))
    soften(r, EqualityRow::soft(error, std::abs(error), row_velocity(rows_[r], J_, step.in->joint_qd.data()),
                                EqualityRow::softness(model_, e, false), step.dt));
  equality_row_[e] = r;
}

void IslandRows::tendon_jacobian(int r, int t, Scalar sign) {
  if (!is_spatial(model_, t)) {
    const int first = model_.tendon_start[t], a = index_.dof_articulation[model_.tendon_dof[first]];
    Scalar* J = row_jacobian(r, a);
    for (int e = first; e < model_.tendon_start[t + 1]; ++e)
      J[model_.tendon_dof[e] - art_[a].qd_begin()] += sign * model_.tendon_coef[e];
    return;
  }
  // each piece: its far end's velocity along it less its near end's (spans_: the tendon's pieces this step)
  for (const TendonSpan& span : spans_)
    for (int k = 0; k < 2; ++k) {
      const int body = span.body[k], a = index_.moving(body);
      if (a >= 0)
        (*route_)[a]->point_jacobian(a, index_.body_link[body], &span.point[k], span.unit,
                                     (k == 1 ? sign : -sign) * span.scale, row_jacobian(r, a));
    }
}

void IslandRows::add_tendon_rows(const StepContext& step, int t) {
  // as a joint's limit rows and dry friction, over the tendon's length and velocity (J: a fixed tendon's
  // coefficients, a spatial one's pieces at the step's body poses)
  for (int k = 0; k < 3; ++k) tendon_row_[3 * t + k] = -1;
  if (!std::isfinite(model_.tendon_limit_lower[t]) && !std::isfinite(model_.tendon_limit_upper[t]) &&
      !FrictionLossRow::on(model_.tendon_frictionloss[t]))
    return;
  const bool spatial = is_spatial(model_, t);
  const Scalar length = spatial ? spatial_tendon(model_, t, step.in->body_q.data(), spans_)
                                : tendon_length(model_, t, step.in->joint_q.data());
  // the articulations it acts on (a spatial tendon's: at most two, the builder's rule)
  int arts[2] = {-1, -1};
  if (!spatial) arts[0] = index_.dof_articulation[model_.tendon_dof[model_.tendon_start[t]]];
  for (int e = model_.tendon_path_start[t]; e < model_.tendon_path_start[t + 1]; ++e) {
    const int a = index_.moving(model_.tendon_path_body[e]);
    if (a >= 0 && a != arts[0] && a != arts[1]) arts[arts[0] < 0 ? 0 : 1] = a;
  }
  if (arts[0] < 0) return;  // (nothing it pulls moves)
  auto tendon_row = [&](RowKind kind, Scalar target, Scalar sign) {
    const int r = begin_row(arts[0], arts[1], kind, target);
    tendon_jacobian(r, t, sign);
    return r;
  };
  // its velocity at the step's velocities and at its start, from a row dropped once read
  const int probe = tendon_row(LimitRow::kKind, 0, 1);
  const Scalar velocity = row_velocity(rows_[probe], J_, step.qd);
  const Scalar start_velocity = row_velocity(rows_[probe], J_, step.in->joint_qd.data());
  drop_last_row();
  for (int side = 0; side < 2; ++side) {
    const Scalar limit = side == 0 ? model_.tendon_limit_lower[t] : model_.tendon_limit_upper[t];
    const Scalar gap = LimitRow::gap(length, limit, side);
    const Softness soft = softness_of(&model_.tendon_limit_solref[2 * t], &model_.tendon_limit_solimp[5 * t],
                                      model_.tendon_invweight0[t]);
    const bool softened = step.settings.soft_constraints && soft.soft();
    if (!LimitRow::on(limit, gap, velocity, side, step.dt, softened)) continue;
    const int r = tendon_row(LimitRow::kKind, LimitRow::target(gap, step.settings, step.dt), LimitRow::sign(side));
    rows_[r].lambda = LimitRow::warm(step.tendon_impulse[3 * t + side], warm_share_of(r, step));
    if (softened) soften(r, LimitRow::soft(gap, LimitRow::sign(side) * start_velocity, soft, step.dt));
    tendon_row_[3 * t + side] = r;
  }
  const Scalar loss = model_.tendon_frictionloss[t];
  if (!FrictionLossRow::on(loss)) return;
  const int r = tendon_row(FrictionLossRow::kKind, 0, 1);
  rows_[r].bound = FrictionLossRow::bound(loss, step.dt);
  rows_[r].lambda = FrictionLossRow::warm(step.tendon_impulse[3 * t + 2], warm_share_of(r, step));
  const Softness soft = softness_of(&model_.tendon_friction_solref[2 * t], &model_.tendon_friction_solimp[5 * t],
                                    model_.tendon_invweight0[t]);
  if (step.settings.soft_constraints && soft.soft()) soften(r, FrictionLossRow::soft(start_velocity, soft, step.dt));
  tendon_row_[3 * t + 2] = r;
}

void IslandRows::keep_constraint_impulses(const StepContext& step) const {
  for (int e = 0; e < model_.equality_count; ++e) {
    for (int k = 0; k < EqualityRow::count(static_cast<EqualityType>(model_.equality_type[e])); ++k)
      step.equality_impulse[6 * e + k] = EqualityRow::keep(rows_[equality_row_[e] + k].lambda, true);
  }
  for (int t = 0; t < 3 * model_.tendon_count; ++t) {
    const int r = tendon_row_[t];
    step.tendon_impulse[t] = KeptImpulseRow::keep(r < 0 ? 0 : rows_[r].lambda, r >= 0);
  }
}

void IslandRows::group_islands() {
  // articulations joined by rows (union-find), then each island's rows in row order, a counting sort
  const int n = static_cast<int>(art_.size());
  island_parent_.resize(n);
  std::iota(island_parent_.begin(), island_parent_.end(), 0);
  auto find = [&](int a) {
    while (island_parent_[a] != a) a = island_parent_[a] = island_parent_[island_parent_[a]];
    return a;
  };
  auto art_of = [&](const PgsRow& row, int side) { return index_.dof_articulation[row.dof_begin[side]]; };
  for (int r = 0; r < row_count_; ++r)
    if (rows_[r].side_count == 2) {
      const int x = find(art_of(rows_[r], 0)), y = find(art_of(rows_[r], 1));
      island_parent_[std::max(x, y)] = std::min(x, y);
    }
  island_of_row_.resize(row_count_);
  for (int r = 0; r < row_count_; ++r)
    island_of_row_[r] = rows_[r].side_count > 0 ? find(art_of(rows_[r], 0)) : 0;  // a row of no dofs does nothing
  island_start_.assign(n + 1, 0);
  for (int r = 0; r < row_count_; ++r) ++island_start_[island_of_row_[r] + 1];
  for (int i = 0; i < n; ++i) island_start_[i + 1] += island_start_[i];
  fill_.assign(island_start_.begin(), island_start_.end() - 1);
  island_rows_.resize(row_count_);
  for (int r = 0; r < row_count_; ++r) island_rows_[fill_[island_of_row_[r]]++] = r;
}

void IslandRows::solve(const StepContext& step, const std::vector<int>& articulations, const std::vector<int>& contacts,
                       int threads) {
  if (row_count_ > 0) {
    group_islands();
    const int n = static_cast<int>(art_.size());
    parallel_for(std::min(threads, n), n, [&](int island) {
      const int begin = island_start_[island], count = island_start_[island + 1] - begin;
      const int* order = island_rows_.data() + begin;
      for (int k = 0; k < count; ++k) finish_row(order[k], step.pgs.cfm);
      for (int k = 0; k < count; ++k) apply_impulse(rows_[order[k]], MinvJT_, rows_[order[k]].lambda, step.qd);
      bool converged = false;
      pgs_solve(rows_, order, count, J_, MinvJT_, step.pgs, step.qd, &converged);
      for (int k = 0; k < count; ++k)
        for (int s = 0; s < rows_[order[k]].side_count; ++s)
          step.pgs_converged[index_.dof_articulation[rows_[order[k]].dof_begin[s]]] = converged;
    });
  }
  // impulses kept for warm starting: contacts as world vectors on body b, limits per dof and side
  for (const int c : contacts) {
    Scalar d[9], lambda[6], P[6];
    contact_frame(&step.contacts->contact_normal[3 * c], d);
    for (int e = 0; e < contact_dims_[c]; ++e) lambda[e] = rows_[contact_row_[c] + e].lambda;
    ContactRows::keep(lambda, contact_dims_[c], d, P);
    std::copy_n(P, 3, &step.contacts->contact_impulse[3 * c]);
    std::copy_n(P + 3, 3, &step.contacts->contact_spin_impulse[3 * c]);
  }
  keep_constraint_impulses(step);
  for (const int a : articulations)
    for (int g = art_[a].qd_begin(); g < art_[a].qd_begin() + art_[a].dof_count(); ++g) {
      const int r = friction_row_[g];
      step.friction_impulse[g] = FrictionLossRow::keep(r < 0 ? 0 : rows_[r].lambda, r >= 0);
    }
  for (const int a : articulations)
    for (int m = limited_start_[a]; m < limited_start_[a + 1]; ++m) {
      const int g = model_.joint_qd_start[limited_joints_[m]];
      for (int side = 0; side < 2; ++side) {
        const int r = limit_row_[2 * g + side];
        step.limit_impulse[limit_cell_[2 * m + side]] = LimitRow::keep(r < 0 ? 0 : rows_[r].lambda, r >= 0);
      }
    }
}

std::size_t IslandRows::bytes() const {
  return (J_.size() + MinvJT_.size()) * sizeof(Scalar) + rows_.size() * sizeof(PgsRow) +
         (limit_row_.size() + friction_row_.size() + contact_row_.size() + equality_row_.size() + tendon_row_.size()) *
             sizeof(int);
}

}  // namespace novaphy
