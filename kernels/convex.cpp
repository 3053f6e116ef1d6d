#include "kernels/convex.h"

#include <ccd/ccd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace novaphy {

namespace {

// a feature is used where its normal is within these of the contact normal: faces (box, hull, cylinder cap)
// where n_face . n > kFaceCos; a cylinder's or capsule's side where |axis . n| < kSideSin
constexpr Scalar kFaceCos = 0.7, kSideSin = 0.3;
constexpr int kCapCorners = 8;  // a cylinder's cap as a regular polygon

// MPR's settings, MuJoCo's defaults (mjOption mpr_tolerance, mpr_iterations)
constexpr Scalar kMprTolerance = 1e-6;
constexpr int kMprIterations = 50;

// the surface patch of a shape facing a direction: a point (count 1), a segment (2) or a polygon (>= 3,
// counterclockwise about its outward normal), in the world frame; id names it among the shape's features
struct Feature {
  std::array<Vec3, 16> p;
  int count = 0;
  Vec3 normal = Vec3::Zero();
  int id = 0;
};

// the local polygon of a box's face k (axis k / 2, sign of k % 2) counterclockwise about its outward normal
void box_face(const Vec3& half, int axis, Scalar sign, Feature* f) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const Scalar su[4] = {1, -1, -1, 1}, sv[4] = {1, 1, -1, -1};
  for (int c = 0; c < 4; ++c) {
    Vec3 x = Vec3::Zero();
    x[axis] = sign * half[axis];
    x[u] = sign * su[c] * half[u];  // (mirrored on the negative face, to stay counterclockwise seen from outside)
    x[v] = sv[c] * half[v];
    f->p[c] = x;
  }
  f->count = 4;
  f->normal = Vec3::Zero();
  f->normal[axis] = sign;
}

// s's feature facing the world direction d (unit); a shape of no such feature gives count 0
Feature feature(const ConvexShape& s, const Vec3& d) {
  Feature f;
  const Vec3 dl = s.pose.q.conjugate() * d;
  switch (s.kind) {
    case ConvexKind::Box: {
      int k;
      const Scalar best = dl.cwiseAbs().maxCoeff(&k);
      if (best > kFaceCos) box_face(s.size, k, dl[k] > 0 ? 1 : -1, &f), f.id = 2 * k + (dl[k] > 0);
      break;
    }
    case ConvexKind::Hull: {
      const HullView& h = *s.hull;
      int best = 0;
      for (int g = 1; g < h.face_count; ++g)
        if (Eigen::Map<const Vec3>(h.face_plane + 4 * g).dot(dl) >
            Eigen::Map<const Vec3>(h.face_plane + 4 * best).dot(dl))
          best = g;
      if (Eigen::Map<const Vec3>(h.face_plane + 4 * best).dot(dl) <= kFaceCos) break;
      // (a face of more than 16 corners by every k-th of them, still counterclockwise and spread all round)
      const int begin = h.corner_start[best], corners = h.corner_start[best + 1] - begin;
      const int stride = (corners + 15) / 16;
      for (int c = 0; c < corners; c += stride)
        f.p[f.count++] = Eigen::Map<const Vec3>(h.vertex + 3 * h.corner[begin + c]);
      f.normal = Eigen::Map<const Vec3>(h.face_plane + 4 * best);
      f.id = best;
      break;
    }
    case ConvexKind::Cylinder:
    case ConvexKind::Capsule: {
      const Scalar r = s.size.x(), hh = s.size.y();
      if (s.kind == ConvexKind::Cylinder && std::abs(dl.y()) > kFaceCos) {
        const Scalar sign = dl.y() > 0 ? 1 : -1;
        for (int c = 0; c < kCapCorners; ++c) {  // counterclockwise about the cap's outward normal
          const Scalar angle = 2 * M_PI * c / kCapCorners;
          f.p[c] = Vec3(r * std::cos(angle), sign * hh, -sign * r * std::sin(angle));
        }
        f.count = kCapCorners;
        f.normal = Vec3(0, sign, 0);
        f.id = dl.y() > 0;
      } else if (std::abs(dl.y()) < kSideSin) {
        const Vec3 out = Vec3(dl.x(), 0, dl.z()).normalized();
        f.p[0] = r * out - Vec3(0, hh, 0);
        f.p[1] = r * out + Vec3(0, hh, 0);
        f.count = 2;
        f.id = 2;
      }
      break;
    }
    case ConvexKind::Sphere:
    case ConvexKind::Ellipsoid: break;
  }
  for (int c = 0; c < f.count; ++c) f.p[c] = s.pose.apply(f.p[c]);
  f.normal = s.pose.q * f.normal;
  return f;
}

// a clipped point with the id of where it came from (an incident corner, or an edge crossing a side plane)
struct Clipped {
  Vec3 p;
  int id;
};
// a convex polygon of 16 corners clipped by one of 16 sides gains at most one corner a side
using ClippedPolygon = std::array<Clipped, 32>;

// the incident feature (a segment or polygon) clipped to the prism over the reference polygon
int clip_to_face(const Feature& ref, const Feature& inc, ClippedPolygon& poly) {
  ClippedPolygon next;
  int count = inc.count;
  for (int c = 0; c < count; ++c) poly[c] = {inc.p[c], c};
  for (int e = 0; e < ref.count && count > 0; ++e) {
    const Vec3& v = ref.p[e];
    const Vec3 out = (ref.p[(e + 1) % ref.count] - v).cross(ref.normal);
    int kept = 0;
    // a segment is an open chain: its one edge, not back again
    const int edges = count == 2 ? 1 : count;
    for (int c = 0; c < count; ++c) {
      const Clipped& p = poly[c];
      const Scalar dp = out.dot(p.p - v);
      if (dp <= 0 && kept < static_cast<int>(next.size())) next[kept++] = p;
      if (c >= edges) continue;
      const Clipped& q = poly[(c + 1) % count];
      const Scalar dq = out.dot(q.p - v);
      if ((dp < 0) != (dq < 0) && dp != dq && kept < static_cast<int>(next.size()))
        next[kept++] = {p.p + (dp / (dp - dq)) * (q.p - p.p), 16 + ((e * 5 + p.id) & 15)};
    }
    count = kept;
    std::copy(next.begin(), next.begin() + count, poly.begin());
  }
  return count;
}

// the manifold of a face against a face, segment or another face: incident points clipped to the reference
// face and kept within the margin; normal from a to b
int face_manifold(const Feature& ref, const Feature& inc, bool ref_is_a, Scalar margin, ContactPoint* out) {
  ClippedPolygon poly;
  const int count = clip_to_face(ref, inc, poly);
  std::array<ContactPoint, std::tuple_size_v<ClippedPolygon>> points;
  int found = 0;
  for (int c = 0; c < count; ++c) {
    const Scalar depth = -ref.normal.dot(poly[c].p - ref.p[0]);
    if (depth < -margin) continue;
    points[found].normal = ref_is_a ? ref.normal : Vec3(-ref.normal);
    points[found].depth = depth;
    points[found].point = poly[c].p + 0.5 * depth * ref.normal;
    const int a_id = ref_is_a ? ref.id : inc.id, b_id = ref_is_a ? inc.id : ref.id;
    points[found].feature = ((a_id & 63) << 10) | ((b_id & 63) << 4) | (poly[c].id & 15);
    ++found;
  }
  found = reduce_to_four(found, points.data());
  std::copy(points.begin(), points.begin() + found, out);
  return found;
}

// two nearly parallel sides (capsules', cylinders'): b's segment clipped to the extent of a's, each end
// against the nearest point of a's line
int segment_manifold(const Feature& fa, const Feature& fb, const Vec3& n, Scalar margin, ContactPoint* out) {
  const Vec3 u = (fa.p[1] - fa.p[0]).normalized(), w = fb.p[1] - fb.p[0];
  if (std::abs(u.dot(w.normalized())) < 0.95) return 0;
  const Scalar length = (fa.p[1] - fa.p[0]).norm(), t0 = u.dot(fb.p[0] - fa.p[0]), t1 = u.dot(fb.p[1] - fa.p[0]);
  if (t0 == t1) return 0;
  int found = 0;
  for (int k = 0; k < 2; ++k) {
    const Scalar t = std::clamp(k == 0 ? t0 : t1, Scalar(0), length);
    const Vec3 q = fb.p[0] + ((t - t0) / (t1 - t0)) * w;
    const Vec3 p = fa.p[0] + u.dot(q - fa.p[0]) * u;
    const Scalar depth = n.dot(p - q);
    if (depth < -margin) continue;
    out[found].normal = n;
    out[found].depth = depth;
    out[found].point = 0.5 * (p + q);
    out[found].feature = 1 + k;
    ++found;
  }
  return found;
}

// the outward unit normal of a smooth shape (sphere, capsule, ellipsoid) at its surface point nearest p, or zero
// for a shape with corners or flat faces
Vec3 smooth_normal(const ConvexShape& s, const Vec3& p) {
  const Vec3 x = s.pose.q.conjugate() * (p - s.pose.p);
  Vec3 n = Vec3::Zero();
  switch (s.kind) {
    case ConvexKind::Sphere: n = x; break;
    case ConvexKind::Capsule: n = x - Vec3(0, std::clamp(x.y(), -s.size.y(), s.size.y()), 0); break;
    case ConvexKind::Ellipsoid: {  // the gradient at x scaled onto the surface
      const Vec3 on = x / x.cwiseQuotient(s.size).norm();
      n = on.cwiseQuotient(s.size.cwiseProduct(s.size));
      break;
    }
    default: return n;
  }
  return n.squaredNorm() > 0 ? Vec3(s.pose.q * n.normalized()) : Vec3::Zero();
}

// libccd's MPR bounds its last phase by max_iterations but not the two before it (discovering and refining the
// portal), which can cycle without end on a nearly degenerate pair. A query's support calls are counted (both
// shapes share the count) and past kMprSupportCalls each shape answers -d: the Minkowski difference's point then
// lies behind the direction searched, which ends either phase as "no contact". A query within the bound (at most
// about 2 x (10 + 30 + kMprIterations) calls) is unchanged
constexpr int kMprSupportCalls = 512;

// libccd's view of a shape: grown by half the margin, its query's count of support calls
struct CcdShape {
  const ConvexShape* shape;
  Scalar grow;
  int* calls;
};

void ccd_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* vertex) {
  const auto* s = static_cast<const CcdShape*>(object);
  const Vec3 d(direction->v[0], direction->v[1], direction->v[2]);
  const Vec3 p = ++*s->calls > kMprSupportCalls ? Vec3(-d) : convex_support(*s->shape, d) + s->grow * d.normalized();
  for (int k = 0; k < 3; ++k) vertex->v[k] = p[k];
}

void ccd_center(const void* object, ccd_vec3_t* center) {
  const Vec3& p = static_cast<const CcdShape*>(object)->shape->pose.p;
  for (int k = 0; k < 3; ++k) center->v[k] = p[k];
}

}  // namespace

Vec3 convex_support(const ConvexShape& s, const Vec3& d) {
  const Vec3 dl = s.pose.q.conjugate() * d;
  Vec3 p = Vec3::Zero();
  switch (s.kind) {
    case ConvexKind::Sphere: p = s.size.x() * dl.normalized(); break;
    case ConvexKind::Box:
      for (int k = 0; k < 3; ++k) p[k] = dl[k] >= 0 ? s.size[k] : -s.size[k];
      break;
    case ConvexKind::Capsule:
      p = Vec3(0, dl.y() >= 0 ? s.size.y() : -s.size.y(), 0) + s.size.x() * dl.normalized();
      break;
    case ConvexKind::Cylinder: {
      const Scalar radial = std::hypot(dl.x(), dl.z());
      p.y() = dl.y() >= 0 ? s.size.y() : -s.size.y();
      if (radial > 0) p.x() = s.size.x() * dl.x() / radial, p.z() = s.size.x() * dl.z() / radial;
      break;
    }
    case ConvexKind::Ellipsoid: {
      const Vec3 scaled = s.size.cwiseProduct(dl);
      p = s.size.cwiseProduct(scaled) / scaled.norm();
      break;
    }
    case ConvexKind::Hull: {
      const HullView& h = *s.hull;
      int best = 0;
      Scalar reach = Eigen::Map<const Vec3>(h.vertex).dot(dl);
      for (int v = 1; v < h.vertex_count; ++v) {
        const Scalar r = Eigen::Map<const Vec3>(h.vertex + 3 * v).dot(dl);
        if (r > reach) reach = r, best = v;
      }
      p = Eigen::Map<const Vec3>(h.vertex + 3 * best);
      break;
    }
  }
  return s.pose.apply(p);
}

int collide_convex(const ConvexShape& a, const ConvexShape& b, Scalar margin, ContactPoint* out) {
  // the deepest point and the normal: MPR on the shapes grown by half the margin each
  int calls = 0;
  const CcdShape ca{&a, 0.5 * margin, &calls}, cb{&b, 0.5 * margin, &calls};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd_support;
  ccd.support2 = ccd_support;
  ccd.center1 = ccd_center;
  ccd.center2 = ccd_center;
  ccd.mpr_tolerance = kMprTolerance;
  ccd.max_iterations = kMprIterations;
  ccd_real_t grown_depth;
  ccd_vec3_t dir, pos;
  if (ccdMPRPenetration(&ca, &cb, &ccd, &grown_depth, &dir, &pos) != 0) return 0;
  Vec3 n(dir.v[0], dir.v[1], dir.v[2]);
  if (!(n.squaredNorm() > 0)) n = Vec3::UnitY();
  n.normalize();
  // the features facing each other: a manifold where a face meets a face or side, two parallel sides
  const Feature fa = feature(a, n), fb = feature(b, -n);
  int count = 0;
  if (fa.count >= 3 && (fb.count == 2 || (fb.count >= 3 && fa.normal.dot(n) >= -fb.normal.dot(n))))
    count = face_manifold(fa, fb, true, margin, out);
  else if (fb.count >= 3 && fa.count >= 2)
    count = face_manifold(fb, fa, false, margin, out);
  else if (fa.count == 2 && fb.count == 2)
    count = segment_manifold(fa, fb, n, margin, out);
  if (count > 0) return count;
  // a single point: MPR's normal, or where a shape is smooth its surface's there (both: their mean)
  const Vec3 at(pos.v[0], pos.v[1], pos.v[2]);
  const Vec3 surface = smooth_normal(a, at) - smooth_normal(b, at);
  if (surface.squaredNorm() > 0 && surface.dot(n) > 0) n = surface.normalized();
  out->normal = n;
  out->depth = grown_depth - margin;
  out->point = Vec3(pos.v[0], pos.v[1], pos.v[2]);
  out->feature = 0;
  return out->depth >= -margin ? 1 : 0;
}

int collide_plane_cylinder(const Transform& plane, const Transform& cylinder, Scalar radius, Scalar half_height,
                           Scalar margin, ContactPoint* out) {
  const Vec3 n = plane.q * Vec3::UnitY(), axis = cylinder.q * Vec3::UnitY();
  const Vec3 u = cylinder.q * Vec3::UnitX(), v = cylinder.q * Vec3::UnitZ();
  // the rim's deepest point of each cap where the cylinder leans (on its side or rim), and four fixed rim points
  // of each (standing on a cap)
  const Vec3 down = -(n - n.dot(axis) * axis);
  const bool leans = down.norm() > 0.1;
  std::array<ContactPoint, 10> candidates;
  int count = 0;
  for (int cap = 0; cap < 2; ++cap) {
    const Vec3 center = cylinder.p + (cap == 0 ? -half_height : half_height) * axis;
    for (int k = leans ? 0 : 1; k < 5; ++k) {
      const Scalar angle = 0.5 * M_PI * (k - 1);
      const Vec3 rim = k == 0 ? Vec3(down.normalized()) : Vec3(std::cos(angle) * u + std::sin(angle) * v);
      if (k > 0 && leans && rim.dot(down.normalized()) > 0.99) continue;  // (the deepest point already)
      const Vec3 p = center + radius * rim;
      const Scalar depth = -n.dot(p - plane.p);
      if (depth < -margin) continue;
      candidates[count++] = {p + 0.5 * depth * n, n, depth, 5 * cap + k};
    }
  }
  count = reduce_to_four(count, candidates.data());
  std::copy(candidates.begin(), candidates.begin() + count, out);
  return count;
}

int collide_plane_ellipsoid(const Transform& plane, const Transform& ellipsoid, const Vec3& radii, Scalar margin,
                            ContactPoint* out) {
  const Vec3 n = plane.q * Vec3::UnitY();
  const Vec3 nl = ellipsoid.q.conjugate() * n, scaled = radii.cwiseProduct(nl);
  const Vec3 p = ellipsoid.apply(-radii.cwiseProduct(scaled) / scaled.norm());
  const Scalar depth = -n.dot(p - plane.p);
  if (depth < -margin) return 0;
  *out = {p + 0.5 * depth * n, n, depth, 0};
  return 1;
}

int collide_plane_hull(const Transform& plane, const Transform& pose, const HullView& hull, Scalar margin,
                       ContactPoint* out) {
  const Vec3 n = plane.q * Vec3::UnitY();
  auto point_at = [&](int v, ContactPoint* c) {
    const Vec3 p = pose.apply(Eigen::Map<const Vec3>(hull.vertex + 3 * v));
    const Scalar depth = -n.dot(p - plane.p);
    *c = {p + 0.5 * depth * n, n, depth, v};
    return depth >= -margin;
  };
  return keep_four(hull.vertex_count, point_at, out);
}

}  // namespace novaphy
