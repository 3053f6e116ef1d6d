#include "kernels/collide.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace novaphy {

namespace {

// the pair as seen from b: normal flipped, same points and depths
int flip(int count, ContactPoint* out) {
  for (int k = 0; k < count; ++k) out[k].normal = -out[k].normal;
  return count;
}

// sphere of radius r at c against a surface point s with outward normal n (towards the sphere)
int sphere_on_surface(const Vec3& c, Scalar r, const Vec3& s, const Vec3& n, Scalar margin, int feature,
                      ContactPoint* out) {
  const Scalar depth = r - n.dot(c - s);
  if (depth < -margin) return 0;
  out->normal = n;
  out->depth = depth;
  out->point = 0.5 * (s + (c - r * n));
  out->feature = feature;
  return 1;
}

Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b, Scalar* t_out = nullptr) {
  const Vec3 d = b - a;
  const Scalar len2 = d.squaredNorm();
  const Scalar t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, Scalar(0), Scalar(1)) : Scalar(0);
  if (t_out) *t_out = t;
  return a + t * d;
}

// closest points of segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision Detection 5.1.9)
void closest_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3* c1, Vec3* c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const Scalar a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  Scalar s = 0, t = 0;
  if (a <= 1e-18 && e <= 1e-18) {
  } else if (a <= 1e-18) {
    t = std::clamp(f / e, Scalar(0), Scalar(1));
  } else {
    const Scalar c = d1.dot(r);
    if (e <= 1e-18) {
      s = std::clamp(-c / a, Scalar(0), Scalar(1));
    } else {
      const Scalar b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-18 ? std::clamp((b * f - c * e) / denom, Scalar(0), Scalar(1)) : Scalar(0);
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, Scalar(0), Scalar(1));
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, Scalar(0), Scalar(1));
      }
    }
  }
  *c1 = p1 + s * d1;
  *c2 = p2 + t * d2;
}

void capsule_ends(const Transform& capsule, Scalar half_height, Vec3* a, Vec3* b) {
  const Vec3 axis = capsule.q * Vec3(0, half_height, 0);
  *a = capsule.p - axis;
  *b = capsule.p + axis;
}

// sphere-sphere as the core of every round pair: centres ca, cb with radii
int spheres(const Vec3& ca, Scalar ra, const Vec3& cb, Scalar rb, Scalar margin, int feature, ContactPoint* out) {
  const Vec3 d = cb - ca;
  const Scalar dist = d.norm();
  const Scalar depth = ra + rb - dist;
  if (depth < -margin) return 0;
  out->normal = dist > 1e-12 ? Vec3(d / dist) : Vec3::UnitY();
  out->depth = depth;
  out->point = 0.5 * ((ca + ra * out->normal) + (cb - rb * out->normal));
  out->feature = feature;
  return 1;
}

}  // namespace

Scalar box_signed_distance(const Vec3& p, const Vec3& half, Vec3* normal) {
  const Vec3 q = p.cwiseAbs() - half;
  if ((q.array() > 0).any()) {
    const Vec3 outside = q.cwiseMax(0);
    const Scalar dist = outside.norm();
    *normal = outside.cwiseProduct(p.cwiseSign()) / dist;
    return dist;
  }
  int k;
  const Scalar dist = q.maxCoeff(&k);
  *normal = Vec3::Zero();
  (*normal)[k] = p[k] >= 0 ? 1 : -1;
  return dist;
}

int reduce_to_four(int count, ContactPoint* points) {
  if (count <= 4) return count;
  std::array<ContactPoint, 4> kept;
  const int found = keep_four(
      count,
      [&](int k, ContactPoint* p) {
        *p = points[k];
        return true;
      },
      kept.data());
  std::copy(kept.begin(), kept.begin() + found, points);
  return found;
}

int collide_plane_sphere(const Transform& plane, const Vec3& center, Scalar radius, Scalar margin, ContactPoint* out) {
  const Vec3 n = plane.q * Vec3::UnitY();
  Scalar point[3], depth;
  if (!plane_sphere_contact<Scalar>(plane.p.data(), n.data(), center.data(), radius, margin, point, &depth)) return 0;
  *out = {Vec3(point[0], point[1], point[2]), n, depth, 0};
  return 1;
}

int collide_plane_box(const Transform& plane, const Transform& box, const Vec3& half, Scalar margin,
                      ContactPoint* out) {
  const Vec3 n = plane.q * Vec3::UnitY();
  int count = 0;
  for (int v = 0; v < 8; ++v) {
    const Vec3 corner((v & 1) ? half.x() : -half.x(), (v & 2) ? half.y() : -half.y(), (v & 4) ? half.z() : -half.z());
    const Vec3 p = box.apply(corner);
    const Scalar depth = -n.dot(p - plane.p);
    if (depth < -margin) continue;
    out[count].normal = n;
    out[count].depth = depth;
    out[count].point = p + 0.5 * depth * n;
    out[count].feature = v;
    ++count;
  }
  return reduce_to_four(count, out);
}

int collide_plane_capsule(const Transform& plane, const Transform& capsule, Scalar radius, Scalar half_height,
                          Scalar margin, ContactPoint* out) {
  Vec3 ends[2];
  capsule_ends(capsule, half_height, &ends[0], &ends[1]);
  int count = 0;
  for (int k = 0; k < 2; ++k) {
    if (collide_plane_sphere(plane, ends[k], radius, margin, out + count) == 0) continue;
    out[count++].feature = k;
  }
  return count;
}

int collide_sphere_sphere(const Vec3& center_a, Scalar radius_a, const Vec3& center_b, Scalar radius_b, Scalar margin,
                          ContactPoint* out) {
  return spheres(center_a, radius_a, center_b, radius_b, margin, 0, out);
}

int collide_sphere_box(const Vec3& center, Scalar radius, const Transform& box, const Vec3& half, Scalar margin,
                       ContactPoint* out) {
  Vec3 n_local;
  const Vec3 p = box.inverse().apply(center);
  const Scalar dist = box_signed_distance(p, half, &n_local);
  const Vec3 n = box.q * n_local;  // box -> sphere
  const Vec3 surface = center - dist * n;
  if (sphere_on_surface(center, radius, surface, n, margin, 0, out) == 0) return 0;
  return flip(1, out);
}

int collide_sphere_capsule(const Vec3& center, Scalar radius, const Transform& capsule, Scalar capsule_radius,
                           Scalar half_height, Scalar margin, ContactPoint* out) {
  Vec3 a, b;
  capsule_ends(capsule, half_height, &a, &b);
  return spheres(center, radius, closest_on_segment(center, a, b), capsule_radius, margin, 0, out);
}

int collide_capsule_capsule(const Transform& a, Scalar radius_a, Scalar half_height_a, const Transform& b,
                            Scalar radius_b, Scalar half_height_b, Scalar margin, ContactPoint* out) {
  Vec3 a0, a1, b0, b1, ca, cb;
  capsule_ends(a, half_height_a, &a0, &a1);
  capsule_ends(b, half_height_b, &b0, &b1);
  closest_segment_segment(a0, a1, b0, b1, &ca, &cb);
  int count = spheres(ca, radius_a, cb, radius_b, margin, 0, out);
  // nearly parallel capsules side by side touch along a line: add both ends of a
  const Vec3 da = (a1 - a0).normalized(), db = (b1 - b0).normalized();
  if (std::abs(da.dot(db)) > 0.98 && count == 1) {
    count = 0;
    for (int k = 0; k < 2; ++k) {
      const Vec3& end = k == 0 ? a0 : a1;
      count += spheres(end, radius_a, closest_on_segment(end, b0, b1), radius_b, margin, 1 + k, out + count);
    }
  }
  return count;
}

int collide_capsule_box(const Transform& capsule, Scalar radius, Scalar half_height, const Transform& box,
                        const Vec3& half, Scalar margin, ContactPoint* out) {
  Vec3 end0, end1;
  capsule_ends(capsule, half_height, &end0, &end1);
  const Transform to_box = box.inverse();
  const Vec3 p0 = to_box.apply(end0), p1 = to_box.apply(end1);
  Vec3 n;
  auto sdf = [&](Scalar t) { return box_signed_distance(p0 + t * (p1 - p0), half, &n); };
  // the signed distance of a convex set is convex along the segment: golden-section search
  Scalar lo = 0, hi = 1;
  const Scalar g = 0.5 * (std::sqrt(5.0) - 1);
  Scalar x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = sdf(x1), f2 = sdf(x2);
  for (int it = 0; it < 48; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = sdf(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = sdf(x2);
    }
  }
  // both ends, and the deepest interior point where it is deeper than the ends (crossing an edge)
  const Scalar t_min = 0.5 * (lo + hi);
  const bool interior = t_min > 1e-3 && t_min < 1 - 1e-3 && sdf(t_min) < std::min(sdf(0), sdf(1)) - 1e-6;
  const Scalar candidates[3] = {0, 1, t_min};
  int count = 0;
  for (int k = 0; k < (interior ? 3 : 2); ++k) {
    const Scalar t = candidates[k];
    const Vec3 p = p0 + t * (p1 - p0);
    const Scalar dist = box_signed_distance(p, half, &n);
    const Vec3 c = box.apply(p), n_world = box.q * n;  // box -> capsule
    if (sphere_on_surface(c, radius, c - dist * n_world, n_world, margin, k, out + count) == 0) continue;
    ++count;
  }
  return flip(count, out);
}

bool boxes_apart(const Transform& a, const Vec3& half_a, const Transform& b, const Vec3& half_b, Scalar margin) {
  // in a's frame: b's axes as the columns of R, its centre at t
  const Mat3 R = a.rotation().transpose() * b.rotation();
  const Vec3 t = a.q.conjugate() * (b.p - a.p);
  const Mat3 abs_R = R.cwiseAbs();
  for (int i = 0; i < 3; ++i)
    if (std::abs(t[i]) - half_a[i] - abs_R.row(i).dot(half_b) > margin) return true;
  for (int j = 0; j < 3; ++j)
    if (std::abs(t.dot(R.col(j))) - abs_R.col(j).dot(half_a) - half_b[j] > margin) return true;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const Scalar length = std::sqrt(std::max(Scalar(0), 1 - R(i, j) * R(i, j)));  // |a_i x b_j|
      if (length < 1e-6) continue;
      const Scalar ra = half_a[i1] * abs_R(i2, j) + half_a[i2] * abs_R(i1, j);
      const Scalar rb = half_b[j1] * abs_R(i, j2) + half_b[j2] * abs_R(i, j1);
      if (std::abs(t[i2] * R(i1, j) - t[i1] * R(i2, j)) - ra - rb > margin * length) return true;
    }
  }
  return false;
}

int collide_box_box(const Transform& a, const Vec3& half_a, const Transform& b, const Vec3& half_b, Scalar margin,
                    ContactPoint* out) {
  const Mat3 Ra = a.rotation(), Rb = b.rotation();
  const Vec3 T = b.p - a.p;
  auto separation = [&](const Vec3& L) {
    Scalar pa = 0, pb = 0;
    for (int k = 0; k < 3; ++k)
      pa += half_a[k] * std::abs(Ra.col(k).dot(L)), pb += half_b[k] * std::abs(Rb.col(k).dot(L));
    return std::abs(T.dot(L)) - pa - pb;
  };

  // separating axis test: 3 + 3 face normals, then 9 edge pairs; faces preferred on near ties
  Scalar best = -std::numeric_limits<Scalar>::infinity();
  int best_axis = -1;
  for (int k = 0; k < 6; ++k) {
    const Vec3 L = k < 3 ? Vec3(Ra.col(k)) : Vec3(Rb.col(k - 3));
    const Scalar s = separation(L);
    if (s > margin) return 0;
    if (s > best + (k >= 3 ? 1e-6 : 0)) best = s, best_axis = k;
  }
  const Scalar best_face = best;
  Vec3 edge_axis;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Vec3 L = Ra.col(i).cross(Rb.col(j));
      const Scalar len = L.norm();
      if (len < 1e-6) continue;
      L /= len;
      const Scalar s = separation(L);
      if (s > margin) return 0;
      if (s > best && s > 0.95 * best_face + 1e-3 * (half_a.minCoeff() + half_b.minCoeff())) {
        best = s, best_axis = 6 + 3 * i + j, edge_axis = L;
      }
    }
  }

  if (best_axis >= 6) {
    // edge-edge: closest points of the two supporting edges
    const int i = (best_axis - 6) / 3, j = (best_axis - 6) % 3;
    Vec3 L = edge_axis;
    if (T.dot(L) < 0) L = -L;
    Vec3 pa = a.p, pb = b.p;
    for (int k = 0; k < 3; ++k) {
      if (k != i) pa += half_a[k] * (Ra.col(k).dot(L) > 0 ? 1 : -1) * Ra.col(k);
      if (k != j) pb -= half_b[k] * (Rb.col(k).dot(L) > 0 ? 1 : -1) * Rb.col(k);
    }
    Vec3 ca, cb;
    closest_segment_segment(pa - half_a[i] * Ra.col(i), pa + half_a[i] * Ra.col(i), pb - half_b[j] * Rb.col(j),
                            pb + half_b[j] * Rb.col(j), &ca, &cb);
    out->normal = L;
    out->depth = -best;
    out->point = 0.5 * (ca + cb);
    out->feature = 1024 + best_axis;
    return 1;
  }

  // face contact: reference face on the box owning the axis, incident face on the other
  const bool ref_is_a = best_axis < 3;
  const Transform& ref = ref_is_a ? a : b;
  const Transform& inc = ref_is_a ? b : a;
  const Mat3& Rr = ref_is_a ? Ra : Rb;
  const Mat3& Ri = ref_is_a ? Rb : Ra;
  const Vec3& hr = ref_is_a ? half_a : half_b;
  const Vec3& hi = ref_is_a ? half_b : half_a;
  const int k = best_axis % 3;
  const Scalar sign = Rr.col(k).dot(inc.p - ref.p) >= 0 ? 1 : -1;
  const Vec3 n = sign * Rr.col(k);  // from reference to incident
  const Vec3 face_center = ref.p + hr[k] * n;

  int j = 0;
  for (int m = 1; m < 3; ++m)
    if (std::abs(Ri.col(m).dot(n)) > std::abs(Ri.col(j).dot(n))) j = m;
  const Scalar inc_sign = Ri.col(j).dot(n) > 0 ? -1 : 1;
  const int u = (j + 1) % 3, v = (j + 2) % 3;
  const Vec3 inc_center = inc.p + inc_sign * hi[j] * Ri.col(j);
  const Vec3 du = hi[u] * Ri.col(u), dv = hi[v] * Ri.col(v);

  // polygon with an id per vertex, unique within the pair: 0..3 incident corners, 4 + 4 * plane + edge
  // where an incident edge crosses a side plane, 20 + corner where two side planes cross (a corner of
  // the reference face); `along` is what the edge to the next vertex lies on: an incident edge 0..3 or
  // the side plane 4 + plane
  struct Vertex {
    Vec3 p;
    int id, along;
  };
  std::array<Vertex, 16> poly{{{inc_center + du + dv, 0, 0},
                               {inc_center - du + dv, 1, 1},
                               {inc_center - du - dv, 2, 2},
                               {inc_center + du - dv, 3, 3}}},
      clipped;
  int count = 4;
  const int ru = (k + 1) % 3, rv = (k + 2) % 3;
  for (int plane = 0; plane < 4; ++plane) {
    const Vec3 axis = (plane < 2 ? Rr.col(ru) : Rr.col(rv)) * (plane % 2 == 0 ? 1 : -1);
    const Scalar limit = plane < 2 ? hr[ru] : hr[rv];
    int next = 0;
    for (int e = 0; e < count; ++e) {
      const Vertex& p = poly[e];
      const Vertex& q = poly[(e + 1) % count];
      const Scalar dp = axis.dot(p.p - ref.p) - limit, dq = axis.dot(q.p - ref.p) - limit;
      if (dp <= 0) clipped[next++] = p;
      if ((dp < 0) != (dq < 0) && dp != dq) {
        // the crossing; leaving the face, the polygon goes on along this side plane
        const int side = p.along - 4;  // (planes 0, 1 cross 2, 3; parallel ones never meet)
        const int id =
            p.along < 4 ? 4 + 4 * plane + p.along : 20 + 2 * (side < 2 ? side : plane) + (side < 2 ? plane : side) - 2;
        clipped[next++] = {p.p + (dp / (dp - dq)) * (q.p - p.p), id, dp < 0 ? 4 + plane : p.along};
      }
    }
    count = next;
    std::copy(clipped.begin(), clipped.begin() + count, poly.begin());
  }

  const int ref_code = (ref_is_a ? 0 : 6) + 2 * k + (sign > 0);
  const int inc_code = 2 * j + (inc_sign > 0);
  std::array<ContactPoint, 16> points;
  int found = 0;
  for (int e = 0; e < count; ++e) {
    const Scalar d = n.dot(poly[e].p - face_center);
    if (d > margin) continue;
    points[found].normal = ref_is_a ? n : Vec3(-n);
    points[found].depth = -d;
    points[found].point = poly[e].p - 0.5 * d * n;
    points[found].feature = (ref_code * 6 + inc_code) * 32 + poly[e].id;
    ++found;
  }
  found = reduce_to_four(found, points.data());
  std::copy(points.begin(), points.begin() + found, out);
  return found;
}

template <typename V>
void shape_bounds(BoundsKind kind, const V* body, const V* local, const V* scale, Scalar margin, V* pose, V* lower,
                  V* upper) {
  const V ax = body[3], ay = body[4], az = body[5], aw = body[6];
  const V bx = local[3], by = local[4], bz = local[5], bw = local[6];
  // p = R(body) local.p + body.p, rotating by t = 2 a x v: v + aw t + a x t
  const V tx = 2 * (ay * local[2] - az * local[1]), ty = 2 * (az * local[0] - ax * local[2]),
          tz = 2 * (ax * local[1] - ay * local[0]);
  pose[0] = local[0] + aw * tx + (ay * tz - az * ty) + body[0];
  pose[1] = local[1] + aw * ty + (az * tx - ax * tz) + body[1];
  pose[2] = local[2] + aw * tz + (ax * ty - ay * tx) + body[2];
  const V x = aw * bx + ax * bw + ay * bz - az * by, y = aw * by - ax * bz + ay * bw + az * bx,
          z = aw * bz + ax * by - ay * bx + az * bw, w = aw * bw - ax * bx - ay * by - az * bz;
  pose[3] = x, pose[4] = y, pose[5] = z, pose[6] = w;
  // how far the shape reaches from its origin along each world axis (a box's and a capsule's through the
  // entries of the rotation, R = R(x, y, z, w) of the unit quaternion)
  V extent[3];
  switch (kind) {
    case BoundsKind::Plane:
      for (V& e : extent) e = V{};
      break;
    case BoundsKind::Sphere:
      for (V& e : extent) e = scale[0];
      break;
    case BoundsKind::Box: {
      const V R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                         {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                         {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
      for (int i = 0; i < 3; ++i)
        extent[i] = bounds_abs(R[i][0]) * scale[0] + bounds_abs(R[i][1]) * scale[1] + bounds_abs(R[i][2]) * scale[2];
      break;
    }
    case BoundsKind::Capsule: {  // the segment's half along R's second column, and the radius
      const V column[3] = {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)};
      for (int i = 0; i < 3; ++i) extent[i] = bounds_abs(column[i]) * scale[1] + scale[0];
      break;
    }
  }
  for (int i = 0; i < 3; ++i) {
    lower[i] = pose[i] - extent[i] - margin;
    upper[i] = pose[i] + extent[i] + margin;
  }
}

template void shape_bounds<Scalar>(BoundsKind, const Scalar*, const Scalar*, const Scalar*, Scalar, Scalar*, Scalar*,
                                   Scalar*);
template void shape_bounds<Lanes<Scalar>>(BoundsKind, const Lanes<Scalar>*, const Lanes<Scalar>*, const Lanes<Scalar>*,
                                          Scalar, Lanes<Scalar>*, Lanes<Scalar>*, Lanes<Scalar>*);

void shape_bounds_lanes_reference(BoundsKind kind, const Lanes<Scalar>* body, const Lanes<Scalar>* local,
                                  const Lanes<Scalar>* scale, Scalar margin, Lanes<Scalar>* pose, Lanes<Scalar>* lower,
                                  Lanes<Scalar>* upper) {
  for (int l = 0; l < kLanes<Scalar>; ++l) {
    Scalar b[7], x[7], s[3], p[7], lo[3], up[3];
    for (int k = 0; k < 7; ++k) b[k] = body[k][l], x[k] = local[k][l];
    for (int k = 0; k < 3; ++k) s[k] = scale[k][l];
    shape_bounds(kind, b, x, s, margin, p, lo, up);
    for (int k = 0; k < 7; ++k) pose[k][l] = p[k];
    for (int k = 0; k < 3; ++k) lower[k][l] = lo[k], upper[k][l] = up[k];
  }
}

}  // namespace novaphy
