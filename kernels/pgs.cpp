#include "kernels/pgs.h"

#include <algorithm>
#include <cmath>

namespace novaphy {

void contact_tangents(const Vec3& n, Vec3* t1, Vec3* t2) {
  const Scalar normal[3] = {n.x(), n.y(), n.z()};
  Scalar d[9];
  contact_frame(normal, d);
  *t1 = Vec3(d[3], d[4], d[5]);
  *t2 = Vec3(d[6], d[7], d[8]);
}

Scalar row_velocity(const PgsRow& row, const std::vector<Scalar>& J, const Scalar* qd) {
  // the innermost loop of PGS: a vector reduction (its order is the build's, the same for every row,
  // world and thread count)
  Scalar v = 0;
  for (int s = 0; s < row.side_count; ++s) {
    const Scalar* j = J.data() + row.pool[s];
    const Scalar* x = qd + row.dof_begin[s];
#pragma omp simd reduction(+ : v)
    for (int k = 0; k < row.dof_count[s]; ++k) v += j[k] * x[k];
  }
  return v;
}

Scalar row_coupling(const PgsRow& a, const PgsRow& b, const std::vector<Scalar>& J, const std::vector<Scalar>& MinvJT) {
  Scalar v = 0;
  for (int s = 0; s < a.side_count; ++s) {
    const Scalar* j = J.data() + a.pool[s];
    const Scalar* z = MinvJT.data() + b.pool[s];
    for (int k = 0; k < a.dof_count[s]; ++k) v += j[k] * z[k];
  }
  return v;
}

void apply_impulse(const PgsRow& row, const std::vector<Scalar>& MinvJT, Scalar impulse, Scalar* qd) {
  for (int s = 0; s < row.side_count; ++s) {
    const Scalar* m = MinvJT.data() + row.pool[s];
    Scalar* x = qd + row.dof_begin[s];
#pragma omp simd
    for (int k = 0; k < row.dof_count[s]; ++k) x[k] += m[k] * impulse;
  }
}

int pgs_solve(std::vector<PgsRow>& rows, const int* order, int count, const std::vector<Scalar>& J,
              const std::vector<Scalar>& MinvJT, const PgsSettings& settings, Scalar* qd, bool* converged) {
  // unconstrained step of one row: the impulse that would bring J qd to its target
  auto step = [&](const PgsRow& row) {
    return -(row_velocity(row, J, qd) - row.target + (settings.cfm + row.cfm) * row.lambda) * row.inv_mass;
  };
  // a row whose impulse moved by more than tolerance / (J M^-1 J^T) keeps the sweeps going (with
  // tolerance 0: moved at all; a sweep that moves none is a fixed point, which every further sweep
  // would repeat bit for bit); an impulse that did not change is not applied (no m * 0 added)
  auto moved = [&](const PgsRow& row, Scalar change) { return std::abs(change) > settings.tolerance * row.inv_mass; };
  int it = 0;
  bool moving = true;
  for (; it < settings.iterations && moving; ++it) {
    moving = false;
    for (int k = 0; k < count; ++k) {
      const int r = order[k];
      PgsRow& row = rows[r];
      if (const int g = cone_after(
              k, count, r, [&](int i) { return rows[order[i]].kind; }, [&](int i) { return rows[order[i]].normal; })) {
        // a contact's normal and friction cone rows: one block update
        const int n = 1 + g;
        ConeBlock<Scalar> block;
        Scalar* A = block.A;
        Scalar lambda[kMaxContact], residual[kMaxContact], mu[kMaxContact], p[kMaxContact];
        for (int i = 0; i < n; ++i) {
          const PgsRow& x = rows[order[k + i]];
          const bool massive = x.inv_mass > 0;
          lambda[i] = x.lambda;
          mu[i] = x.mu;
          residual[i] = massive ? row_velocity(x, J, qd) - x.target + (settings.cfm + x.cfm) * x.lambda : 0;
          A[i * kMaxContact + i] = massive ? 1 / x.inv_mass : 1;
          for (int j = 0; j < i; ++j)
            A[i * kMaxContact + j] = A[j * kMaxContact + i] = row_coupling(x, rows[order[k + j]], J, MinvJT);
        }
        block.prepare(n - 1);
        solve_contact_cone(block, lambda, residual, mu + 1, settings.friction_smoothing, p);
        for (int i = 0; i < n; ++i) {
          PgsRow& x = rows[order[k + i]];
          if (!std::isfinite(p[i]) || p[i] == x.lambda) continue;
          apply_impulse(x, MinvJT, p[i] - x.lambda, qd);
          moving |= moved(x, p[i] - x.lambda);
          x.lambda = p[i];
        }
        k += n - 1;
        continue;
      }
      if (row.kind == RowKind::FrictionCone) continue;  // (updated with its normal row only)
      // a row touching a diverged articulation yields no impulse, so NaN does not spread through contacts
      if (row.kind != RowKind::FrictionPair) {
        const Scalar unclamped = row.lambda + step(row);
        const Scalar bound = row.kind == RowKind::FrictionOne ? row.mu * rows[row.normal].lambda : row.bound;
        const Scalar lambda =
            row.kind == RowKind::Unilateral ? project_unilateral(unclamped) : project_bounded(unclamped, bound);
        if (!std::isfinite(lambda) || lambda == row.lambda) continue;
        apply_impulse(row, MinvJT, lambda - row.lambda, qd);
        moving |= moved(row, lambda - row.lambda);
        row.lambda = lambda;
        continue;
      }
      // friction pair: both tangents, bounded by mu * normal impulse (box, disk or a blend)
      PgsRow& second = rows[r + 1];
      const Scalar limit = row.mu * rows[row.normal].lambda;
      const Scalar l1 = row.lambda + step(row), l2 = second.lambda + step(second);
      Scalar new1, new2;
      project_friction_pair(l1, l2, limit, settings.friction_smoothing, &new1, &new2);
      ++k;  // the second tangent
      if (!std::isfinite(new1) || !std::isfinite(new2)) continue;
      if (new1 != row.lambda) apply_impulse(row, MinvJT, new1 - row.lambda, qd);
      if (new2 != second.lambda) apply_impulse(second, MinvJT, new2 - second.lambda, qd);
      moving |= moved(row, new1 - row.lambda) || moved(second, new2 - second.lambda);
      row.lambda = new1;
      second.lambda = new2;
    }
  }
  if (converged) *converged = !moving;
  return it;
}

}  // namespace novaphy
