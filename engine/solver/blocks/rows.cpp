// The Rows stage of one block: its worlds' joint-limit rows and contact rows (the parts of
// engine/solver/parts/rows.h in lanes), swept by batch_pgs_solve, the impulses kept for the next step. A lane's
// absent rows are masked, so a world's result does not depend on its block-mates.
#include "engine/solver/parts/rows.h"

#include <chrono>

#include "engine/solver/blocks/block_data.h"

namespace novaphy {

namespace {

template <typename T>
using V = Lanes<T>;

// a new row of R (J and M^-1 J^T not yet written), on in the lanes `on`, starting from `warm`
template <typename T>
int add_row(RowWork<T>& R, RowKind kind, const IntLanes<T>& on, const V<T>& target, const V<T>& warm) {
  const int r = R.rows++;
  R.kind[r] = kind;
  R.normal[r] = -1;
  R.active[r] = on;
  R.target[r] = target;
  R.lambda[r] = on ? warm : V<T>{};
  R.mu[r] = V<T>{};
  R.cfm[r] = V<T>{};
  R.nonzero_begin[r] = R.dofs;
  R.nonzero_end[r] = 0;
  R.zero_begin[r] = R.zero_end[r] = 0;
  return r;
}

// row r's J = sign e_k in the lanes `on` (0 in the others), copied into M^-1 J^T for solve_rows
template <typename T>
void unit_row(int nv, int k, T sign, const IntLanes<T>& on, int r, RowWork<T>& R) {
  V<T>* J = R.J_row(r);
  std::fill(J, J + nv, V<T>{});
  J[k] = on ? V<T>{} + sign : V<T>{};
  std::copy(J, J + nv, R.z_row(r));
  R.nonzero_begin[r] = k;
  R.nonzero_end[r] = k + 1;
}

// M^-1 J^T of the rows from `first` on, from J^T written in place and the block's factor H: all of them together
// (their chains of operations side by side)
template <typename T>
void solve_rows(const BatchTopology<T>& topo, const Lanes<T>* H, int first, RowWork<T>& R) {
  int end = 0;
  for (int r = first; r < R.rows; ++r) end = std::max(end, R.nonzero_end[r]);
  batch_solve_many(topo, H, end, R.z_row(first), R.rows - first, topo.dof_count);
}

// row r soft in the lanes `soft` (its cfm and target), from each lane's softness
template <typename T, typename Soften>
void soften_lanes(const IntLanes<T>& soft, const Softness* softness, int r, RowWork<T>& R, Soften&& soften) {
  for (int l = 0; l < kLanes<T>; ++l) {
    if (!soft[l]) continue;
    const SoftRow row = soften(l, softness[l]);
    R.target[r][l] = static_cast<T>(row.target);
    R.cfm[r][l] = static_cast<T>(row.cfm);
  }
}

// the rows of the limited dofs in dof order, J = +-e_k, in the lanes `mine` whose joint would cross a limit; soft
// ones read R.qd_in
template <typename T>
void add_limit_rows(const BatchGroup<T>& G, int b, const StepContext& step, const BatchWork<T>& w,
                    const IntLanes<T>& mine, RowWork<T>& R) {
  const BatchTopology<T>& topo = G.topo;
  const int nl = static_cast<int>(G.limited.size());
  const V<T> dt = splat<V<T>>(static_cast<T>(step.dt));
  const V<T>* limit = G.limits.data() + static_cast<size_t>(b) * 2 * nl;  // (empty without limits)
  const Scalar* kept = step.limit_impulse + G.impulse_base + static_cast<size_t>(b) * 2 * nl * kLanes<T>;
  for (int m = 0; m < nl; ++m) {
    const int k = G.limited[m];
    const V<T> q = w.q[topo.coord_of_dof[k]];
    const Softness* softness = &G.limit_softness[(static_cast<size_t>(b) * nl + m) * kLanes<T>];
    const IntLanes<T> soft =
        G.soft_limits && step.settings.soft_constraints ? G.limit_soft[static_cast<size_t>(b) * nl + m] : IntLanes<T>{};
    for (int side = 0; side < 2; ++side) {
      const V<T> gap = LimitRow::gap(q, limit[2 * m + side], side);
      const IntLanes<T> on = mine & LimitRow::on(limit[2 * m + side], gap, w.qd[k], side, dt, soft);
      R.limit_row[2 * m + side] = -1;
      if (!any_lane<T>(on)) continue;
      const V<T> warm = LimitRow::warm(lanes_from_doubles<T>(kept + (2 * m + side) * kLanes<T>), R.warm_share);
      const int r = add_row(R, LimitRow::kKind, on, LimitRow::target(gap, step.settings, dt), warm);
      R.limit_row[2 * m + side] = r;
      unit_row(topo.dof_count, k, T(LimitRow::sign(side)), on, r, R);
      soften_lanes(on & soft, softness, r, R, [&](int l, const Softness& s) {
        return LimitRow::soft(gap[l], LimitRow::sign(side) * R.qd_in[k][l], s, step.dt);
      });
    }
  }
}

// a row per dof with dry friction, J = e_k, in the lanes `mine` whose world has it: its velocity driven to
// zero with at most frictionloss dt of impulse either way; soft ones read R.qd_in
template <typename T>
void add_friction_rows(const BatchGroup<T>& G, int b, const StepContext& step, const IntLanes<T>& mine, RowWork<T>& R) {
  const int nf = static_cast<int>(G.frictional.size());
  const V<T>* loss = G.frictionloss.data() + static_cast<size_t>(b) * nf;
  const V<T> dt = splat<V<T>>(static_cast<T>(step.dt));
  for (int m = 0; m < nf; ++m) {
    const int k = G.frictional[m];
    const IntLanes<T> on = mine & FrictionLossRow::on(loss[m]);
    R.friction_row[m] = -1;
    if (!any_lane<T>(on)) continue;
    V<T> kept;
    gather_lanes<T>(&G.qd_off[b * kLanes<T>], step.friction_impulse + k, 1, &kept);
    const int r = add_row(R, FrictionLossRow::kKind, on, V<T>{}, FrictionLossRow::warm(kept, R.warm_share));
    R.bound[r] = FrictionLossRow::bound(loss[m], dt);
    R.friction_row[m] = r;
    unit_row(G.topo.dof_count, k, T(1), on, r, R);
    if (G.soft_friction && step.settings.soft_constraints)
      soften_lanes(on & G.friction_soft[static_cast<size_t>(b) * nf + m],
                   &G.friction_softness[(static_cast<size_t>(b) * nf + m) * kLanes<T>], r, R,
                   [&](int l, const Softness& s) { return FrictionLossRow::soft(R.qd_in[k][l], s, step.dt); });
  }
}

// slot t of the contact rows: each lane's t-th listed contact read into lanes (n, p relative to o, its input), its
// links (b, a) per lane; returns the lanes that have one, and in `uniform` the lane whose links every other such lane
// shares (-2: none does)
template <typename T>
IntLanes<T> read_contacts(const BatchGroup<T>& G, int b, int t, const int* listed, const Lanes<T>* o,
                          const StepContext& step, RowWork<T>& R, V<T>* n, V<T>* p, ContactInput<V<T>>& in,
                          int (*link)[2], int* uniform) {
  const Contacts& C = *step.contacts;
  const ContactLists& lists = step.lists;
  IntLanes<T> on{};
  *uniform = -1;
  for (int l = 0; l < kLanes<T>; ++l) {
    const int c = t < listed[l] ? lists.list[lists.start[G.arts[b * kLanes<T> + l]] + t] : -1;
    R.contact[t * kLanes<T> + l] = c;
    if (c < 0) continue;
    on[l] = -1;
    for (int m = 0; m < 3; ++m) {
      n[m][l] = static_cast<T>(C.contact_normal[3 * c + m]);
      p[m][l] = static_cast<T>(C.contact_point[3 * c + m] - o[m][l]);
    }
    ContactRows::set_lane(in, l, ContactRows::read(C, c, *lists.shapes, lists.model->impratio));
    // the links holding the bodies in this articulation (-1: a static body)
    const ArticulationIndex& index = *lists.index;
    const int ba = C.contact_body_a[c], bb = C.contact_body_b[c];
    link[l][0] = index.moving(bb) >= 0 ? index.body_link[bb] : -1;
    link[l][1] = index.moving(ba) >= 0 ? index.body_link[ba] : -1;
    if (*uniform == -1) *uniform = l;
    if (*uniform >= 0 && (link[l][0] != link[*uniform][0] || link[l][1] != link[*uniform][1])) *uniform = -2;
  }
  return on;
}

// where a slot's rows are nonzero: the dofs [begin, end) less the quads [skip_begin, skip_end) (BatchRows')
struct RowSpan {
  int begin, end, skip_begin, skip_end;
};

// R.coef_k: +1 for the dofs on body b's path, -1 on body a's (the relative velocity is b's point's minus
// a's), set for all lanes at once where they share their links; returns the dofs some lane has: their range,
// less the longest run of whole quads between (another branch's dofs)
template <typename T>
RowSpan contact_paths(const BatchTopology<T>& topo, const IntLanes<T>& on, const int (*link)[2], int uniform,
                      RowWork<T>& R) {
  const int nv = topo.dof_count;
  for (int j = 0; j < nv; ++j) R.coef[j] = V<T>{};
  auto add_paths = [&](int l, auto&& add) {
    for (int side = 0; side < 2; ++side) {
      if (link[l][side] < 0) continue;
      for (int e = topo.link_dof_start[link[l][side]]; e < topo.link_dof_start[link[l][side] + 1]; ++e)
        add(topo.link_dofs[e], side == 0 ? T(1) : T(-1));
    }
  };
  if (uniform >= 0) {
    const V<T> one = on ? V<T>{} + 1 : V<T>{};
    add_paths(uniform, [&](int j, T sign) { R.coef[j] += sign * one; });
  } else {
    for (int l = 0; l < kLanes<T>; ++l)
      if (on[l]) add_paths(l, [&](int j, T sign) { R.coef[j][l] += sign; });
  }
  RowSpan span{nv, 0, 0, 0};
  for (int j = 0; j < nv; ++j) {
    if (!any_lane<T>(R.coef[j] != 0)) continue;
    const int skip_begin = (span.end + 3) & ~3, skip_end = j & ~3;
    if (span.end > 0 && skip_end - skip_begin > span.skip_end - span.skip_begin)
      span.skip_begin = skip_begin, span.skip_end = skip_end;
    span.begin = std::min(span.begin, j);
    span.end = j + 1;
  }
  return span;
}

// slot t's normal row and two friction rows; where the model has condim 4 or 6, a torsional row and two rolling
// rows (in the lanes whose contact has them)
template <typename T>
void add_contact_rows(const BatchGroup<T>& G, int b, int t, const int* listed, const BlockKinematics<T>& kin,
                      const StepContext& step, RowWork<T>& R) {
  const BatchTopology<T>& topo = G.topo;
  const int nv = topo.dof_count;
  V<T> n[3] = {}, p[3] = {};
  ContactInput<V<T>> in;
  int link[kLanes<T>][2];
  int uniform;
  const IntLanes<T> on = read_contacts(G, b, t, listed, kin.o, step, R, n, p, in, link, &uniform);
  const RowSpan span = contact_paths(topo, on, link, uniform, R);
  V<T>* d = &R.frame[9 * t];
  contact_frame<Lanes<T>>(n, d);
  V<T> warm[6];
  ContactRows::warm(in, d, ContactRows::warm_share<V<T>>(step.settings), warm);
  // u_k = S_lin,k + S_ang,k x p: the velocity of the point p moved by dof k, once for the three rows
  V<T>* u = R.point.data();
  for (int j = 0; j < nv; ++j) point_velocity(kin.S + 6 * j, p, u + 3 * j);
  const int first = R.rows, dims = step.lists.dims;
  for (int e = 0; e < dims; ++e) {
    // the normal and sliding rows in every lane of `on`; the torsional and rolling ones where its condim has them
    const IntLanes<T> has = on & ContactRows::has(e, in.condim);
    const int r = add_row(R, ContactRows::kind(e, dims), has, V<T>{}, warm[e]);
    V<T>* J = R.J_row(r);
    const V<T>* de = ContactRows::direction(d, e);
    if (!ContactRows::turns(e)) {  // J_k = coef_k d . u_k: the velocity along d of the point p moved by dof k
      for (int j = 0; j < nv; ++j) J[j] = R.coef[j] * (de[0] * u[3 * j] + de[1] * u[3 * j + 1] + de[2] * u[3 * j + 2]);
    } else {  // J_k = coef_k axis . S_ang,k: the relative angular velocity about the normal or a tangent
      for (int j = 0; j < nv; ++j) {
        const V<T>* s = kin.S + 6 * j;
        J[j] = has ? R.coef[j] * (de[0] * s[0] + de[1] * s[1] + de[2] * s[2]) : V<T>{};
      }
    }
    std::copy(J, J + nv, R.z_row(r));
    R.normal[r] = first;
    R.nonzero_begin[r] = span.begin;
    R.nonzero_end[r] = span.end;
    R.zero_begin[r] = span.skip_begin;
    R.zero_end[r] = span.skip_end;
  }
  // the rows' velocities at the step's start; their targets, cfm and friction
  V<T> v[6] = {};
  for (int e = 0; e < dims; ++e)
    for (int j = 0; j < nv; ++j) v[e] += R.J_row(first + e)[j] * R.qd_in[j];
  ContactRows::targets(in, v, dims, step.settings, splat<V<T>>(static_cast<T>(step.dt)), &R.target[first],
                       &R.cfm[first], &R.mu[first]);
}

// the sweeps over the block's rows; returns the lanes whose sweeps converged
template <typename T>
IntLanes<T> sweep(RowWork<T>& R, int nv, const PgsSettings& pgs, V<T>* qd) {
  const BatchRows<T> rows{R.rows,
                          nv,
                          R.kind.data(),
                          R.normal.data(),
                          R.J.data(),
                          R.nonzero_begin.data(),
                          R.nonzero_end.data(),
                          R.zero_begin.data(),
                          R.zero_end.data(),
                          R.z.data(),
                          R.target.data(),
                          R.cfm.data(),
                          R.mu.data(),
                          R.bound.data(),
                          R.active.data(),
                          R.inv_mass.data(),
                          R.lambda.data()};
  IntLanes<T> converged;
  batch_pgs_solve(rows, pgs, qd, &converged);
  return converged;
}

// the impulses kept for warm starting: limits per dof and side, contacts as world vectors on body b
template <typename T>
void keep_impulses(const BatchGroup<T>& G, int b, int slots, const IntLanes<T>& mine, const StepContext& step,
                   const RowWork<T>& R) {
  const int nl = static_cast<int>(G.limited.size());
  Scalar* kept = step.limit_impulse + G.impulse_base + static_cast<size_t>(b) * 2 * nl * kLanes<T>;
  for (int m = 0; m < 2 * nl; ++m) {
    const int r = R.limit_row[m];
    const V<T> x = r >= 0 ? LimitRow::keep(R.lambda[r], R.active[r]) : V<T>{};
    doubles_from_lanes<T>(x, mine, kept + m * kLanes<T>);
  }
  for (size_t m = 0; m < G.frictional.size(); ++m) {
    const int r = R.friction_row[m];
    const V<T> x = r >= 0 ? FrictionLossRow::keep(R.lambda[r], R.active[r]) : V<T>{};
    scatter_lanes<T>(&G.qd_off[b * kLanes<T>], &x, 1, mine, step.friction_impulse + G.frictional[m]);
  }
  const int dims = step.lists.dims;
  for (int t = 0; t < slots; ++t) {
    V<T> P[6];
    ContactRows::keep(&R.lambda[R.rows - dims * (slots - t)], dims, &R.frame[9 * t], P);
    for (int l = 0; l < kLanes<T>; ++l) {
      const int c = R.contact[t * kLanes<T> + l];
      if (c < 0) continue;
      for (int m = 0; m < 3; ++m) {
        step.contacts->contact_impulse[3 * c + m] = P[m][l];
        step.contacts->contact_spin_impulse[3 * c + m] = P[3 + m][l];
      }
    }
  }
}

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point* mark) {
  const Clock::time_point now = Clock::now();
  const double s = std::chrono::duration<double>(now - *mark).count();
  *mark = now;
  return s;
}

}  // namespace

template <typename T>
void block_rows(const BatchGroup<T>& G, int b, const BlockKinematics<T>& kin, const StepContext& step, BatchWork<T>& w,
                RowWork<T>& R, bool carried, bool carry_on, RowPhaseSeconds* phases) {
  constexpr int W = kLanes<T>;
  const int nl = static_cast<int>(G.limited.size()), nf = static_cast<int>(G.frictional.size());
  const int nv = G.topo.dof_count, lanes = G.lanes_in(b);
  const int* qd_off = &G.qd_off[b * W];
  // the lanes whose rows are solved here (the others' are the islands'), each one's contacts, their most
  IntLanes<T> mine{}, converged{};
  int listed[W] = {}, slots = 0;
  for (int l = 0; l < lanes; ++l) {
    const int a = G.arts[b * W + l];
    if (step.touched && step.touched[a]) continue;
    mine[l] = -1;
    converged[l] = step.pgs_converged[a] ? -1 : 0;
    listed[l] = step.lists.start[a + 1] - step.lists.start[a];
    slots = std::max(slots, listed[l]);
  }
  if (!any_lane<T>(mine) || (nl == 0 && nf == 0 && slots == 0)) {
    if (carried && !carry_on) scatter_lanes<T>(qd_off, w.qd.data(), nv, real_lanes(G, b), step.qd);
    return;
  }
  if (!carried) {
    gather_lanes<T>(&G.q_off[b * W], step.in->joint_q.data(), G.topo.coord_count, w.q.data());
    gather_lanes<T>(qd_off, step.qd, nv, w.qd.data());
  }
  Clock::time_point mark = phases ? Clock::now() : Clock::time_point{};
  R.resize(2 * nl + nf + step.lists.dims * slots, nv, slots);
  R.rows = 0;
  R.warm_share = warm_share<V<T>>(converged, step.settings);
  const bool soft = (G.soft_limits || G.soft_friction) && step.settings.soft_constraints;
  if (slots > 0 || soft) gather_lanes<T>(qd_off, step.in->joint_qd.data(), nv, R.qd_in.data());
  add_limit_rows(G, b, step, w, mine, R);
  add_friction_rows(G, b, step, mine, R);
  solve_rows(G.topo, kin.H, 0, R);
  if (phases) phases->limits += seconds_since(&mark);
  const int contact_rows = R.rows;
  for (int t = 0; t < slots; ++t) add_contact_rows(G, b, t, listed, kin, step, R);
  solve_rows(G.topo, kin.H, contact_rows, R);
  if (phases) phases->contacts += seconds_since(&mark);
  converged = sweep(R, nv, step.pgs, w.qd.data());
  for (int l = 0; l < lanes; ++l)
    if (mine[l]) step.pgs_converged[G.arts[b * W + l]] = converged[l] != 0;
  keep_impulses(G, b, slots, mine, step, R);
  if (phases) phases->sweeps += seconds_since(&mark);
  if (!carry_on) scatter_lanes<T>(qd_off, w.qd.data(), nv, carried ? real_lanes(G, b) : mine, step.qd);
}

template struct RowWork<float>;
template struct RowWork<double>;
template void block_rows(const BatchGroup<float>&, int, const BlockKinematics<float>&, const StepContext&,
                         BatchWork<float>&, RowWork<float>&, bool, bool, RowPhaseSeconds*);
template void block_rows(const BatchGroup<double>&, int, const BlockKinematics<double>&, const StepContext&,
                         BatchWork<double>&, RowWork<double>&, bool, bool, RowPhaseSeconds*);

}  // namespace novaphy
