// Projected Gauss-Seidel over velocity constraint rows in joint space (sequential impulses,
// Catto 2005; Featherstone RBDA chapter 11 for the joint-space form). A row acts on the dofs of
// one or two articulations through J (its Jacobian row over each side's dofs) and M^-1 J^T.
#pragma once

#include <limits>
#include <vector>

#include "kernels/number.h"
#include "kernels/spatial.h"

namespace novaphy {

// Unilateral: impulse >= 0 (a contact's normal, a limit); FrictionPair: two tangent rows bounded together by
// mu times their normal row's impulse (sliding, or rolling about the tangents); Bounded: |impulse| <= bound (a
// joint's dry friction); FrictionOne: |impulse| <= mu times its normal row's impulse (torsional friction);
// FrictionCone: a contact's 2 to kMaxCone friction rows (sliding, torsional, rolling: the consecutive rows of this
// kind and normal, right after their normal row) bounded together in MuJoCo's elliptic cone, the vector
// (impulse_i / mu_i) within the ball of radius the normal's impulse; the sweeps update the normal row and them as one
// block (solve_contact_cone)
enum class RowKind : int { Unilateral = 0, FrictionPair = 1, Bounded = 2, FrictionOne = 3, FrictionCone = 4 };

// the most friction rows of one FrictionCone: two sliding, one torsional, two rolling; with the normal row
constexpr int kMaxCone = 5;
constexpr int kMaxContact = kMaxCone + 1;

struct PgsRow {
  RowKind kind = RowKind::Unilateral;  // a FrictionPair row is followed by its second tangent row
  int side_count = 1;
  int dof_begin[2] = {0, 0};  // first dof of each side in the global velocity vector
  int dof_count[2] = {0, 0};
  int pool[2] = {0, 0};  // offset of each side's J and M^-1 J^T in the pools
  Scalar cfm = 0;        // the row's own constraint force mixing, beyond the settings' (a soft contact's)
  Scalar inv_mass = 0;   // 1 / (J M^-1 J^T + settings.cfm + cfm)
  Scalar target = 0;     // the velocity J qd the row drives towards
  Scalar lambda = 0;     // accumulated impulse
  int normal = -1;       // FrictionPair, FrictionOne, FrictionCone: the row holding the normal impulse
  Scalar mu = 0;         // FrictionPair, FrictionOne, FrictionCone: friction coefficient
  Scalar bound = 0;      // Bounded: the largest |impulse|
};

struct PgsSettings {
  int iterations = 20;  // sweeps at most
  Scalar cfm = 0;
  Scalar friction_smoothing = 1;  // 0: box friction per tangent, 1: circular cone, between: blend
  // the sweeps stop early once one sweep moved no row's impulse by more than tolerance / (J M^-1 J^T),
  // i.e. no row's own velocity by more than tolerance (m/s, rad/s); 0: once one sweep moved no impulse
  // at all (a fixed point: the sweeps left would repeat it bit for bit)
  Scalar tolerance = 0;
};

// a contact's frame d [9] from its unit normal n [3]: the normal, then two unit tangents t1 and t2 completing it to
// a right-handed frame (Frisvad's construction), over the number type (kernels/number.h: one contact, or one a
// lane). A lane with n = 0 gets finite numbers
template <typename V>
inline void contact_frame(const V* n, V* d) {
  const V sign = unit_sign(n[2]);
  const V a = Element<V>(-1) / (sign + n[2]), b = n[0] * n[1] * a;
  for (int m = 0; m < 3; ++m) d[m] = n[m];
  d[3] = 1 + sign * n[0] * n[0] * a;
  d[4] = sign * b;
  d[5] = -sign * n[0];
  d[6] = b;
  d[7] = sign + n[1] * n[1] * a;
  d[8] = -n[1];
}

// contact_frame's tangents of the normal n
void contact_tangents(const Vec3& n, Vec3* t1, Vec3* t2);

// a row's 1 / (J M^-1 J^T + cfm) from jmj = J M^-1 J^T and its cfm (the settings' and its own), 0 for a row of no
// mass (at most 1e-12): the effective mass both sweeps scale a row's velocity error by
template <typename V>
inline V row_inv_mass(const V& jmj, const V& cfm) {
  const V w = jmj + cfm;
  return select<V>(w > Element<V>(1e-12), 1 / w, V{});
}

// ---- a row's impulse projected onto its bounds in a sweep, over the number type: one row (pgs_solve) or a row
// of a block's lanes (batch_pgs_solve). A NaN stays NaN or becomes a bound; the sweeps skip a non-finite impulse

// Unilateral: at least 0
template <typename V>
inline V project_unilateral(const V& impulse) {
  return select<V>(impulse > 0, impulse, V{});
}

// Bounded and FrictionOne: within [-bound, bound]
template <typename V>
inline V project_bounded(const V& impulse, const V& bound) {
  return select<V>(impulse < -bound, -bound, select<V>(impulse > bound, bound, impulse));
}

// FrictionPair: the two tangents' impulses l1, l2 within limit (mu times the normal's impulse), *p1 and *p2: each
// clamped to the limit (a box, smoothing 0), the pair scaled into the disk of that radius (1), or a blend
template <typename V>
inline void project_friction_pair(const V& l1, const V& l2, const V& limit, Element<V> smoothing, V* p1, V* p2) {
  const V box1 = project_bounded(l1, limit), box2 = project_bounded(l2, limit);
  // (not hypot: its guard against overflow costs more than the rest of the pair's update)
  const V norm = root(l1 * l1 + l2 * l2);
  const V scale = select<V>(norm > limit, limit / norm, splat<V>(1));
  *p1 = (1 - smoothing) * box1 + smoothing * scale * l1;
  *p2 = (1 - smoothing) * box2 + smoothing * scale * l2;
}

// a small symmetric positive semidefinite matrix B [g x g] (row-major, stride kMaxCone) factored B = L L^T, over the
// number type; a pivot at most kDrop times its diagonal (a row the ones before it span: B singular there) is dropped:
// solve gives it 0 and solves the rest without it
template <typename V>
struct SmallCholesky {
  static constexpr Element<V> kDrop = 1000 * std::numeric_limits<Element<V>>::epsilon();
  int g = 0;
  V L[kMaxCone][kMaxCone];
  V inv[kMaxCone];  // 1 / L_ii, 0 for a dropped pivot

  void factor(const V* B, int n) {
    g = n;
    for (int i = 0; i < g; ++i) {
      for (int j = 0; j < i; ++j) {
        V s = B[i * kMaxCone + j];
        for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
        L[i][j] = s * inv[j];
      }
      V s = B[i * kMaxCone + i];
      for (int k = 0; k < i; ++k) s -= L[i][k] * L[i][k];
      const Mask<V> kept = s > kDrop * B[i * kMaxCone + i];
      L[i][i] = root(select<V>(kept, s, splat<V>(1)));
      inv[i] = select<V>(kept, 1 / L[i][i], V{});
    }
  }
  // x = B^-1 y
  void solve(const V* y, V* x) const {
    V z[kMaxCone];
    for (int i = 0; i < g; ++i) {
      V s = y[i];
      for (int k = 0; k < i; ++k) s -= L[i][k] * z[k];
      z[i] = s * inv[i];
    }
    for (int i = g - 1; i >= 0; --i) {
      V s = z[i];
      for (int k = i + 1; k < g; ++k) s -= L[k][i] * x[k];
      x[i] = s * inv[i];
    }
  }
};

// a friction coefficient below this bounds a cone's row as this (MuJoCo's mjMINMU)
constexpr double kMinMu = 1e-5;
// Newton steps of a cone's projection, at most (a lane stops where its step moved t by under sqrt(epsilon) of it)
constexpr int kConeNewton = 8;
// below this a cone's normal impulse counts as none (MuJoCo's mjMINVAL)
constexpr double kMinImpulse = 1e-15;

// a contact's block for solve_contact_cone, made once for its sweeps: A [(1 + g) x (1 + g), stride kMaxContact], the
// rows' J_i M^-1 J_j^T with each row's cfm on the diagonal, its normal row first (the caller fills it), then its
// friction rows' block and that block's factors (prepare)
template <typename V>
struct ConeBlock {
  int g = 0;  // friction rows
  V A[kMaxContact * kMaxContact];
  V friction[kMaxCone * kMaxCone];
  SmallCholesky<V> factors;

  void prepare(int friction_rows) {
    g = friction_rows;
    for (int i = 0; i < g; ++i)
      for (int j = 0; j < g; ++j) friction[i * kMaxCone + j] = A[(i + 1) * kMaxContact + j + 1];
    factors.factor(friction, g);
  }
};

// FrictionCone: a contact's friction rows' new impulses p [g], the block update of MuJoCo's elliptic cone. The
// block's friction rows (ConeBlock: A their J_i M^-1 J_j^T, each row's cfm on the diagonal); lambda: their impulses;
// r: their residuals J qd - target + cfm lambda. The unconstrained minimiser l = lambda - A^-1 r where it is within
// the cone sum (l_i / mu_i)^2 <= normal^2; else the point of the cone's surface nearest l in A's metric:
// p(t) = (A + t D)^-1 A l, D = diag(1 / mu_i^2), t > 0 where |p|_D = normal (Newton on 1 / |p(t)|_D, nearly linear in
// t), then scaled onto the surface. Smoothing 0: each row of l clamped to mu_i normal instead; between: a blend
template <typename V>
inline void solve_friction_cone(const ConeBlock<V>& block, const V* lambda, const V* r, const V* mu_in, const V& normal,
                                Element<V> smoothing, V* p) {
  using E = Element<V>;
  const int g = block.g;
  const V* A = block.friction;
  V mu[kMaxCone], D[kMaxCone], y[kMaxCone];
  for (int i = 0; i < g; ++i) {
    mu[i] = select<V>(mu_in[i] > static_cast<E>(kMinMu), mu_in[i], splat<V>(static_cast<E>(kMinMu)));
    D[i] = 1 / (mu[i] * mu[i]);
    y[i] = -r[i];
    for (int j = 0; j < g; ++j) y[i] += A[i * kMaxCone + j] * lambda[j];  // A l = A lambda - r
  }
  auto norm_D = [&](const V* x) {
    V s{};
    for (int i = 0; i < g; ++i) s += D[i] * x[i] * x[i];
    return root(s);
  };
  V l[kMaxCone];
  block.factors.solve(y, l);
  const Mask<V> outside = both<Mask<V>>(norm_D(l) > normal, normal > 0);
  for (int i = 0; i < g; ++i) p[i] = l[i];
  if (any_set<V>(outside)) {
    const E settled = std::sqrt(std::numeric_limits<E>::epsilon());
    SmallCholesky<V> moved;
    const SmallCholesky<V>* factors = &block.factors;  // of A + t D
    Mask<V> going = outside;
    V t{};
    for (int k = 0; k < kConeNewton && any_set<V>(going); ++k) {
      // dp/dt = -(A + t D)^-1 D p: Newton's step on 1 / |p(t)|_D - 1 / normal
      V Dp[kMaxCone], q[kMaxCone], B[kMaxCone * kMaxCone];
      for (int i = 0; i < g; ++i) Dp[i] = D[i] * p[i];
      factors->solve(Dp, q);
      V S{}, Q{};
      for (int i = 0; i < g; ++i) S += Dp[i] * p[i], Q += Dp[i] * q[i];
      const V dt = (root(S) / normal - 1) * S / Q;
      const Mask<V> step = both<Mask<V>>(going, both<Mask<V>>(Q > 0, dt > 0));
      t = select<V>(step, t + dt, t);
      going = both<Mask<V>>(step, dt > settled * t);
      for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j) B[i * kMaxCone + j] = A[i * kMaxCone + j] + (i == j ? t * D[i] : V{});
      moved.factor(B, g);
      factors = &moved;
      moved.solve(y, p);
    }
  }
  const V norm = norm_D(p);
  const V scale = select<V>(both<Mask<V>>(outside, norm > 0), normal / norm, splat<V>(1));
  for (int i = 0; i < g; ++i) {
    const V box = project_bounded(l[i], mu[i] * normal);
    p[i] = (1 - smoothing) * box + smoothing * select<V>(normal > 0, scale * p[i], V{});
  }
}

// a contact's normal row and its FrictionCone rows, [1 + g]: their new impulses p, MuJoCo's elliptic block update (its
// PGS's), of its block (ConeBlock, prepared), lambda its rows' impulses and r their residuals as solve_friction_cone's,
// the normal first. The normal impulse: where it is none, its own step (at least 0); else the block's impulse scaled
// along itself to the minimum (a ray, kept in the cone). Then the friction rows solve_friction_cone's within the new
// normal impulse, their residuals moved by the normal's change. Its fixed points are the convex cone problem's, as
// MuJoCo's: a sliding contact's rows leave a separating normal velocity (mu times the slip, the regularised cone's),
// which a normal row stepped on its own would not
template <typename V>
inline void solve_contact_cone(const ConeBlock<V>& block, const V* lambda, const V* r, const V* mu,
                               Element<V> smoothing, V* p) {
  using E = Element<V>;
  const int g = block.g, n = g + 1;
  const V* A = block.A;
  const V& normal = lambda[0];
  V ray{}, denom{};  // lambda . r, lambda . A lambda
  for (int i = 0; i < n; ++i) {
    V row{};
    for (int j = 0; j < n; ++j) row += A[i * kMaxContact + j] * lambda[j];
    ray += lambda[i] * r[i];
    denom += lambda[i] * row;
  }
  const V x = select<V>(denom > static_cast<E>(kMinImpulse), -ray / denom, V{});
  const V along = normal * select<V>(x < -1, V{}, 1 + x);
  const V own = project_unilateral(normal - r[0] / A[0]);
  p[0] = select<V>(normal < static_cast<E>(kMinImpulse), own, along);
  const V change = p[0] - normal;
  V rt[kMaxCone];
  for (int i = 0; i < g; ++i) rt[i] = r[i + 1] + A[(i + 1) * kMaxContact] * change;
  solve_friction_cone(block, lambda + 1, rt, mu, p[0], smoothing, p + 1);
  const Mask<V> none = p[0] < static_cast<E>(kMinImpulse);
  for (int i = 1; i < n; ++i) p[i] = select<V>(none, V{}, p[i]);
}

// the FrictionCone rows of the contact whose normal row is at position `at` of a sweep (0: that row is no such normal):
// the rows after it of kind FrictionCone and its normal, at most kMaxCone, none at `end` or past it. kind(i) and
// normal(i): the kind and normal row of the row at position i; self: the normal row's own index, as normal() gives it
template <typename Kind, typename Normal>
inline int cone_after(int at, int end, int self, Kind kind, Normal normal) {
  if (kind(at) != RowKind::Unilateral) return 0;
  int g = 0;
  while (g < kMaxCone && at + 1 + g < end && kind(at + 1 + g) == RowKind::FrictionCone && normal(at + 1 + g) == self)
    ++g;
  return g;
}

// J qd of one row
Scalar row_velocity(const PgsRow& row, const std::vector<Scalar>& J, const Scalar* qd);

// J_a M^-1 J_b^T of two rows over the same sides and dofs (a contact's)
Scalar row_coupling(const PgsRow& a, const PgsRow& b, const std::vector<Scalar>& J, const std::vector<Scalar>& MinvJT);

// qd += M^-1 J^T * impulse for one row
void apply_impulse(const PgsRow& row, const std::vector<Scalar>& MinvJT, Scalar impulse, Scalar* qd);

// sweeps the rows order[0 .. count) in that order (a friction pair's second row follows its first)
// inputs:  rows with lambda as the warm start (already applied to qd), the pools
// outputs: rows[].lambda, qd; *converged (if given): whether the sweeps stopped at one that moved no row beyond
//          the tolerance (false where they ran out); returns the sweeps run
int pgs_solve(std::vector<PgsRow>& rows, const int* order, int count, const std::vector<Scalar>& J,
              const std::vector<Scalar>& MinvJT, const PgsSettings& settings, Scalar* qd, bool* converged = nullptr);

}  // namespace novaphy
