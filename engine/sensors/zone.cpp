#include "engine/sensors/zone.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace novaphy {

namespace {

constexpr Scalar kInf = std::numeric_limits<Scalar>::infinity();

// the interval of t where a x t^2 + b t + c <= 0 holds (a >= 0): empty as lo > hi
void quadratic_interval(Scalar a, Scalar b, Scalar c, Scalar& lo, Scalar& hi) {
  if (a <= 0) {
    lo = c <= 0 ? -kInf : kInf;
    hi = c <= 0 ? kInf : -kInf;
    return;
  }
  const Scalar disc = b * b - 4 * a * c;
  if (disc < 0) {
    lo = kInf, hi = -kInf;
    return;
  }
  const Scalar root = std::sqrt(disc);
  lo = (-b - root) / (2 * a);
  hi = (-b + root) / (2 * a);
}

// the interval of t where |o_k + t d_k| <= h
void slab_interval(Scalar o, Scalar d, Scalar h, Scalar& lo, Scalar& hi) {
  if (d == 0) {
    lo = std::abs(o) <= h ? -kInf : kInf;
    hi = std::abs(o) <= h ? kInf : -kInf;
    return;
  }
  const Scalar t1 = (-h - o) / d, t2 = (h - o) / d;
  lo = std::min(t1, t2);
  hi = std::max(t1, t2);
}

// whether [lo, hi] meets t >= 0
bool ahead(Scalar lo, Scalar hi) { return lo <= hi && hi >= 0; }

// the interval of t inside the ellipsoid of semi-axes s
bool meets_ellipsoid(const Vec3& s, const Vec3& o, const Vec3& d) {
  const Vec3 os = o.cwiseQuotient(s), ds = d.cwiseQuotient(s);
  Scalar lo, hi;
  quadratic_interval(ds.squaredNorm(), 2 * os.dot(ds), os.squaredNorm() - 1, lo, hi);
  return ahead(lo, hi);
}

bool meets_cylinder(Scalar r, Scalar h, const Vec3& o, const Vec3& d) {
  Scalar lo, hi, zlo, zhi;
  quadratic_interval(d.head<2>().squaredNorm(), 2 * o.head<2>().dot(d.head<2>()), o.head<2>().squaredNorm() - r * r, lo,
                     hi);
  slab_interval(o.z(), d.z(), h, zlo, zhi);
  return ahead(std::max(lo, zlo), std::min(hi, zhi));
}

}  // namespace

bool ray_meets_zone(ShapeType type, const Vec3& size, const Vec3& origin, const Vec3& direction) {
  switch (type) {
    case ShapeType::Sphere: return meets_ellipsoid(Vec3::Constant(size[0]), origin, direction);
    case ShapeType::Ellipsoid: return meets_ellipsoid(size, origin, direction);
    case ShapeType::Box: {
      Scalar lo = -kInf, hi = kInf;
      for (int k = 0; k < 3; ++k) {
        Scalar a, b;
        slab_interval(origin[k], direction[k], size[k], a, b);
        lo = std::max(lo, a);
        hi = std::min(hi, b);
      }
      return ahead(lo, hi);
    }
    case ShapeType::Cylinder: return meets_cylinder(size[0], size[1], origin, direction);
    case ShapeType::Capsule: {
      const Vec3 cap(0, 0, size[1]);
      const Vec3 r = Vec3::Constant(size[0]);
      return meets_cylinder(size[0], size[1], origin, direction) || meets_ellipsoid(r, origin - cap, direction) ||
             meets_ellipsoid(r, origin + cap, direction);
    }
    default: return false;
  }
}

}  // namespace novaphy
