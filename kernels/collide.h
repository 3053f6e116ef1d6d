// The broad phase's shape bounds and plane distances, for one shape or a world per lane (first below);
// the narrow phase: contact points between pairs of primitive shapes (reference kernels).
// Every function writes the points of shape a against shape b within `margin` of touching:
//   normal  unit, pointing from a to b
//   depth   penetration (> 0 overlapping, < 0 a gap smaller than the margin)
//   point   midway between the two surfaces, world frame
//   feature an id that stays the same while the same features touch (warm starting)
// and returns how many it wrote. Planes are the local XZ plane of their frame, normal +Y;
// capsules run along their local Y axis (radius, half height of the segment); boxes take half extents.
#pragma once

#include <algorithm>
#include <limits>

#include "kernels/lanes.h"
#include "kernels/spatial.h"

namespace novaphy {

// The world pose and axis-aligned bounds of a shape on a body: pose = body * local (transforms
// [px, py, pz, qx, qy, qz, qw]), lower and upper = pose's origin -+ (the shape's extent along each
// world axis + margin). scale: a sphere's radius; a box's half extents; a capsule's radius and half
// height; a plane's bounds are its origin. V is Scalar (one shape) or Lanes<Scalar> (one shape in each
// of kLanes worlds, the broad phase of worlds alike): one formula, so both give the same bits
// (shape_bounds_lanes_reference, its twin, calls the Scalar one lane by lane)
enum class BoundsKind { Plane, Sphere, Box, Capsule };
template <typename V>
void shape_bounds(BoundsKind kind, const V* body, const V* local, const V* scale, Scalar margin, V* pose, V* lower,
                  V* upper);
void shape_bounds_lanes_reference(BoundsKind kind, const Lanes<Scalar>* body, const Lanes<Scalar>* local,
                                  const Lanes<Scalar>* scale, Scalar margin, Lanes<Scalar>* pose, Lanes<Scalar>* lower,
                                  Lanes<Scalar>* upper);

// |x| of one number or of every lane
inline Scalar bounds_abs(Scalar x) { return std::abs(x); }
inline Lanes<Scalar> bounds_abs(const Lanes<Scalar>& x) { return lane_abs<Scalar>(x); }

// whether the boxes [la, ua] and [lb, ub] overlap (touching counts): a bool, or a mask per lane
template <typename V>
inline auto boxes_overlap(const V* la, const V* ua, const V* lb, const V* ub) {
  return (lb[0] <= ua[0]) & (la[0] <= ub[0]) & (lb[1] <= ua[1]) & (la[1] <= ub[1]) & (lb[2] <= ua[2]) &
         (la[2] <= ub[2]);
}

// the signed distance from the plane through p with unit normal n to the nearest point of the box
// [lower, upper] (<= 0: the box reaches the plane); V as in shape_bounds, one formula for both
template <typename V>
inline V plane_box_distance(const V* p, const V* n, const V* lower, const V* upper) {
  V distance = n[0] * (Scalar(0.5) * (lower[0] + upper[0]) - p[0]), reach = bounds_abs(n[0]) * (upper[0] - lower[0]);
  for (int k = 1; k < 3; ++k) {
    distance += n[k] * (Scalar(0.5) * (lower[k] + upper[k]) - p[k]);
    reach += bounds_abs(n[k]) * (upper[k] - lower[k]);
  }
  return distance - Scalar(0.5) * reach;
}

struct ContactPoint {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();
  Scalar depth = 0;
  int feature = 0;
};

constexpr int kMaxPairContacts = 8;

// of the candidate points k < count (point_at(k, &p): whether k is one, and p), up to 4 into out: the deepest,
// then repeatedly the one farthest from those kept; returns how many
template <typename PointAt>
int keep_four(int count, PointAt&& point_at, ContactPoint* out) {
  int kept[4], found = 0;
  ContactPoint p, best_point;
  for (int k = 0; k < count; ++k)
    if (point_at(k, &p) && (found == 0 || p.depth > out[0].depth)) kept[0] = k, out[0] = p, found = 1;
  for (; found > 0 && found < 4; ++found) {
    int best = -1;
    Scalar best_d = -1;
    for (int k = 0; k < count; ++k) {
      if (std::find(kept, kept + found, k) != kept + found || !point_at(k, &p)) continue;
      Scalar d = std::numeric_limits<Scalar>::infinity();
      for (int j = 0; j < found; ++j) d = std::min(d, (p.point - out[j].point).squaredNorm());
      if (d > best_d) best_d = d, best = k, best_point = p;
    }
    if (best < 0) break;
    kept[found] = best;
    out[found] = best_point;
  }
  return found;
}
// points[0 .. count) reduced to keep_four's, in their order; returns how many are left
int reduce_to_four(int count, ContactPoint* points);

// a sphere (centre c, radius r) against a plane (a point o on it, unit normal n): its depth and contact point
// (normal n, feature 0), and whether it is a contact (depth >= -margin, as a mask where V is lanes). V is Scalar or
// lanes of pairs, one function for both: a world's contact is the same bits whether found alone or in lanes
template <typename V>
inline auto plane_sphere_contact(const V* o, const V* n, const V* c, const V& r, const V& margin, V* point, V* depth) {
  const V d = n[0] * (c[0] - o[0]) + n[1] * (c[1] - o[1]) + n[2] * (c[2] - o[2]);
  *depth = r - d;
  for (int m = 0; m < 3; ++m) point[m] = 0.5 * ((c[m] - n[m] * d) + (c[m] - r * n[m]));
  return (*depth < -margin) == 0;
}
int collide_plane_sphere(const Transform& plane, const Vec3& center, Scalar radius, Scalar margin, ContactPoint* out);
int collide_plane_box(const Transform& plane, const Transform& box, const Vec3& half, Scalar margin, ContactPoint* out);
int collide_plane_capsule(const Transform& plane, const Transform& capsule, Scalar radius, Scalar half_height,
                          Scalar margin, ContactPoint* out);
int collide_sphere_sphere(const Vec3& center_a, Scalar radius_a, const Vec3& center_b, Scalar radius_b, Scalar margin,
                          ContactPoint* out);
int collide_sphere_box(const Vec3& center, Scalar radius, const Transform& box, const Vec3& half, Scalar margin,
                       ContactPoint* out);
int collide_sphere_capsule(const Vec3& center, Scalar radius, const Transform& capsule, Scalar capsule_radius,
                           Scalar half_height, Scalar margin, ContactPoint* out);
int collide_capsule_capsule(const Transform& a, Scalar radius_a, Scalar half_height_a, const Transform& b,
                            Scalar radius_b, Scalar half_height_b, Scalar margin, ContactPoint* out);
int collide_capsule_box(const Transform& capsule, Scalar radius, Scalar half_height, const Transform& box,
                        const Vec3& half, Scalar margin, ContactPoint* out);
// separating axes, then the incident face clipped against the reference face: up to 4 points
int collide_box_box(const Transform& a, const Vec3& half_a, const Transform& b, const Vec3& half_b, Scalar margin,
                    ContactPoint* out);

// whether boxes a and b (centred at their poses, half extents along their axes) are farther apart than `margin`
// along one of the separating axis test's fifteen axes (an edge pair's only where the edges are not parallel): where
// they are, so are any shapes inside them, which the narrow phase then need not search
bool boxes_apart(const Transform& a, const Vec3& half_a, const Transform& b, const Vec3& half_b, Scalar margin);

// signed distance from a point (box frame) to a box, and the outward normal of the nearest surface
Scalar box_signed_distance(const Vec3& p, const Vec3& half, Vec3* normal);

}  // namespace novaphy
