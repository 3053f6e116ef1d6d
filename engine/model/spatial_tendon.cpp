#include "engine/model/spatial_tendon.h"

#include <algorithm>
#include <cmath>

namespace novaphy {

namespace {

constexpr Scalar kTiny = 1e-15;  // (MuJoCo's mjMINVAL)
constexpr Scalar kPi = 3.14159265358979323846;

using Vec2 = Eigen::Matrix<Scalar, 2, 1>;

Scalar cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// whether the 2D segments a0-a1 and b0-b1 cross
bool segments_cross(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1) {
  const Vec2 da = a1 - a0, db = b1 - b0;
  const Scalar det = cross2(da, db);
  if (std::abs(det) < kTiny) return false;
  const Scalar s = cross2(b0 - a0, db) / det, u = cross2(b0 - a0, da) / det;
  return s >= 0 && s <= 1 && u >= 0 && u <= 1;
}

// the signed angle the segment a-b turns through about the origin (counterclockwise positive, within (-pi, pi])
Scalar turn(const Vec2& a, const Vec2& b) { return std::atan2(cross2(a, b), a.dot(b)); }

// the wrap of the plane's segment e0-e1 around the circle of radius r at the origin: the arc's length and its ends
// t0, t1, or -1 where the path stays straight. Without a side (null) the shorter way round where the segment crosses
// the circle; with one (a point on the circle) the shortest path that turns about the centre as e0 -> side -> e1 does
// (MuJoCo 4's side site: the path homotopic to that polyline with the circle removed)
Scalar wrap_circle(const Vec2& e0, const Vec2& e1, const Vec2* side, Scalar r, Vec2& t0, Vec2& t1) {
  const Scalar r2 = r * r, l0 = e0.squaredNorm(), l1 = e1.squaredNorm();
  if (l0 < r2 || l1 < r2 || r < kTiny) return -1;  // an end inside the circle
  const Vec2 d = e1 - e0;
  const Scalar dd = d.squaredNorm();
  if (dd < kTiny) return -1;
  const Vec2 nearest = e0 + std::clamp(-d.dot(e0) / dd, Scalar(0), Scalar(1)) * d;
  const bool clear = nearest.squaredNorm() > r2;  // the straight segment misses the circle
  if (clear && !side) return -1;
  // the tangent points from each end, one pair on either side: pair 0 turns clockwise round the circle, pair 1
  // counterclockwise; each arc's length (MuJoCo's: the short arc between the points, or its complement where the
  // pair turns the other way)
  const Scalar s0 = std::sqrt(l0 - r2), s1 = std::sqrt(l1 - r2);
  Vec2 pair[2][2];
  Scalar arc[2];
  for (int i = 0; i < 2; ++i) {
    const Scalar sign = i == 0 ? 1 : -1;
    pair[i][0] = Vec2(e0.x() * r2 + sign * r * e0.y() * s0, e0.y() * r2 - sign * r * e0.x() * s0) / l0;
    pair[i][1] = Vec2(e1.x() * r2 - sign * r * e1.y() * s1, e1.y() * r2 + sign * r * e1.x() * s1) / l1;
    Scalar angle = std::acos(std::clamp(pair[i][0].normalized().dot(pair[i][1].normalized()), Scalar(-1), Scalar(1)));
    const Scalar ccw = cross2(pair[i][0], pair[i][1]);
    if ((ccw > 0 && i == 0) || (ccw < 0 && i == 1)) angle = 2 * kPi - angle;
    arc[i] = angle;
  }
  int i;
  if (side) {
    // the path of the side's winding: straight where the segment turns so, else the wrap that does
    const Scalar winding = turn(e0, *side) + turn(*side, e1);
    auto wrapped = [&](int k) { return turn(e0, pair[k][0]) + (k == 0 ? -arc[k] : arc[k]) + turn(pair[k][1], e1); };
    const Scalar off[2] = {std::abs(wrapped(0) - winding), std::abs(wrapped(1) - winding)};
    if (clear && std::abs(turn(e0, e1) - winding) < std::min(off[0], off[1])) return -1;
    i = off[0] < off[1] ? 0 : 1;
  } else {
    // the shorter way, never a pair whose tangents cross
    Scalar good[2];
    for (int k = 0; k < 2; ++k)
      good[k] = segments_cross(e0, pair[k][0], e1, pair[k][1]) ? -10000 : -(pair[k][0] - pair[k][1]).squaredNorm();
    i = good[0] > good[1] ? 0 : 1;
    if (segments_cross(e0, pair[i][0], e1, pair[i][1])) return -1;
  }
  t0 = pair[i][0];
  t1 = pair[i][1];
  return r * arc[i];
}

// the wrap of e0-e1 around the circle of radius r from inside (a side site within the circle): the point t of the
// circle where the path's two straight pieces make equal angles with the radius (both ends t), arc length 0; -1
// where the segment crosses the circle or an end is inside it
Scalar wrap_inside(const Vec2& e0, const Vec2& e1, Scalar r, Vec2& t) {
  const Scalar n0 = e0.norm(), n1 = e1.norm();
  if (n0 <= r || n1 <= r || r < kTiny || n0 < kTiny || n1 < kTiny) return -1;
  const Vec2 d = e1 - e0;
  const Scalar dd = d.squaredNorm();
  if (dd > kTiny) {
    const Scalar a = -d.dot(e0) / dd;
    if (a > 0 && a < 1 && (e0 + a * d).norm() <= r) return -1;
  }
  t = (0.5 * (e0 + e1)).normalized() * r;  // (where the solve fails: the ends' mean direction)
  // the angle z = sin of the tangent's angle solves asin(A z) + asin(B z) - 2 asin(z) + G = 0 (Newton from z near 1)
  const Scalar A = r / n0, B = r / n1, cosG = (n0 * n0 + n1 * n1 - dd) / (2 * n0 * n1);
  if (cosG < -1 + kTiny) return -1;
  if (cosG > 1 - kTiny) return 0;
  const Scalar G = std::acos(cosG);
  auto f_of = [&](Scalar z) { return std::asin(A * z) + std::asin(B * z) - 2 * std::asin(z) + G; };
  Scalar z = 1 - 1e-7, f = f_of(z);
  if (f > 0) return 0;
  int iteration = 0;
  for (; iteration < 20 && std::abs(f) > 1e-6; ++iteration) {
    const Scalar slope = A / std::max(kTiny, std::sqrt(1 - z * z * A * A)) +
                         B / std::max(kTiny, std::sqrt(1 - z * z * B * B)) - 2 / std::max(kTiny, std::sqrt(1 - z * z));
    if (slope > -kTiny) return 0;
    const Scalar next = z - f / slope;
    if (next > z) return 0;
    z = next;
    f = f_of(z);
    if (f > 1e-6) return 0;
  }
  if (iteration >= 20) return 0;
  // turned from the end on the counterclockwise side by the tangent's angle
  const bool from_first = cross2(e0, e1) > 0;
  const Vec2 from = (from_first ? e0 : e1).normalized();
  const Scalar angle = std::asin(z) - std::asin((from_first ? A : B) * z);
  t = r * Vec2(std::cos(angle) * from.x() - std::sin(angle) * from.y(),
               std::sin(angle) * from.x() + std::cos(angle) * from.y());
  return 0;
}

// body b's centre of mass in the world at the pose table body_q
Vec3 com_in(const Model& model, const Scalar* body_q, int b) {
  return pose_in(body_q, b).apply(Vec3(model.body_com[3 * b], model.body_com[3 * b + 1], model.body_com[3 * b + 2]));
}

}  // namespace

Scalar wrap_around(TendonPathKind type, const Transform& geom, Scalar r, const Vec3& x0, const Vec3& x1,
                   const Vec3* side, Vec3& w0, Vec3& w1) {
  // the ends in the geom's frame, and the plane of the wrap: a sphere's through its centre and both ends (any plane
  // through the first end where they are in line with the centre), a cylinder's across its axis
  const Transform to_geom = geom.inverse();
  const Vec3 p0 = to_geom.apply(x0), p1 = to_geom.apply(x1);
  if (p0.norm() < kTiny || p1.norm() < kTiny) return -1;
  Vec3 axis0 = Vec3::UnitX(), axis1 = Vec3::UnitY();
  if (type == TendonPathKind::Sphere) {
    axis0 = p0.normalized();
    Vec3 normal = p0.cross(p1);
    if (normal.norm() < kTiny) {
      const Vec3 a = axis0.cwiseAbs();
      const int big = a[1] > a[0] && a[1] > a[2] ? 1 : a[2] > a[0] && a[2] > a[1] ? 2 : 0;
      Vec3 other = Vec3::Ones();
      other[big] = 0;
      normal = axis0.cross(other);
    }
    normal.normalize();
    axis1 = normal.cross(axis0).normalized();
  }
  const Vec2 e0(p0.dot(axis0), p0.dot(axis1)), e1(p1.dot(axis0), p1.dot(axis1));
  Vec2 t0, t1;
  Scalar length;
  Vec3 s = Vec3::Zero();
  if (side) s = to_geom.apply(*side);
  if (side && s.norm() < r) {
    length = wrap_inside(e0, e1, r, t0);
    t1 = t0;
  } else {
    const Vec2 toward = side ? Vec2(Vec2(s.dot(axis0), s.dot(axis1)).normalized() * r) : Vec2(Vec2::Zero());
    length = wrap_circle(e0, e1, side ? &toward : nullptr, r, t0, t1);
  }
  if (length < 0) return -1;
  Vec3 a = axis0 * t0.x() + axis1 * t0.y(), b = axis0 * t1.x() + axis1 * t1.y();
  if (type == TendonPathKind::Cylinder) {
    // along the axis the path climbs evenly over its unrolled length: a helix on the cylinder
    const Scalar before = (p0.head<2>() - a.head<2>()).norm(), after = (p1.head<2>() - b.head<2>()).norm();
    const Scalar total = before + length + after;
    a.z() = p0.z() + (p1.z() - p0.z()) * before / total;
    b.z() = p0.z() + (p1.z() - p0.z()) * (before + length) / total;
    length = std::hypot(length, b.z() - a.z());
  }
  w0 = geom.apply(a);
  w1 = geom.apply(b);
  return length;
}

Scalar spatial_tendon(const Model& model, int t, const Scalar* body_q, std::vector<TendonSpan>& spans) {
  // inputs: the path (sites, wraps with their side sites, pulleys), the bodies' poses; outputs: the length, the
  // straight pieces
  spans.clear();
  const int begin = model.tendon_path_start[t], end = model.tendon_path_start[t + 1];
  auto kind = [&](int e) { return static_cast<TendonPathKind>(model.tendon_path_kind[e]); };
  auto at = [&](int e) {
    return pose_in(body_q, model.tendon_path_body[e]) * Transform::from_array(&model.tendon_path_frame[7 * e]);
  };
  Scalar length = 0, scale = 1;
  auto straight = [&](int b0, const Vec3& x0, int b1, const Vec3& x1) {
    const Scalar d = (x1 - x0).norm();
    length += scale * d;
    spans.push_back({{b0, b1}, {x0, x1}, d > kTiny ? Vec3((x1 - x0) / d) : Vec3::Zero(), scale});
  };
  for (int e = begin; e < end;) {
    if (kind(e) == TendonPathKind::Pulley) {
      scale = 1 / model.tendon_path_size[e];
      ++e;
      continue;
    }
    // a site, then the next site straight or around the geom between them (the builder's rule: a path is sites,
    // pulleys between sites, a wrap between two sites)
    const int next = e + 1;
    if (next >= end || kind(next) == TendonPathKind::Pulley) {
      e = next;
      continue;
    }
    const int b0 = model.tendon_path_body[e];
    const Vec3 x0 = at(e).p;
    if (kind(next) == TendonPathKind::Site) {
      straight(b0, x0, model.tendon_path_body[next], at(next).p);
      e = next;
      continue;
    }
    const bool sided = kind(next + 1) == TendonPathKind::SideSite;
    const int last = next + (sided ? 2 : 1), wrapped = model.tendon_path_body[next], b1 = model.tendon_path_body[last];
    const Vec3 x1 = at(last).p;
    Vec3 side, w0, w1;
    if (sided) side = at(next + 1).p;
    const Scalar arc =
        wrap_around(kind(next), at(next), model.tendon_path_size[next], x0, x1, sided ? &side : nullptr, w0, w1);
    if (arc < 0) {
      straight(b0, x0, b1, x1);
    } else {
      straight(b0, x0, wrapped, w0);
      length += scale * arc;
      straight(wrapped, w1, b1, x1);
    }
    e = last;
  }
  return length;
}

Scalar spatial_tendon_velocity(const Model& model, const std::vector<TendonSpan>& spans, const Scalar* body_q,
                               const Scalar* body_qd) {
  auto velocity = [&](int b, const Vec3& x) {
    if (b < 0) return Vec3(Vec3::Zero());
    const Scalar* qd = body_qd + 6 * static_cast<size_t>(b);
    return Vec3(Vec3(qd[0], qd[1], qd[2]) + Vec3(qd[3], qd[4], qd[5]).cross(x - com_in(model, body_q, b)));
  };
  Scalar v = 0;
  for (const TendonSpan& s : spans)
    v += s.scale * s.unit.dot(velocity(s.body[1], s.point[1]) - velocity(s.body[0], s.point[0]));
  return v;
}

void add_spatial_tendon_force(const Model& model, const std::vector<TendonSpan>& spans, const Scalar* body_q, Scalar f,
                              Scalar* body_f) {
  for (const TendonSpan& s : spans)
    for (int k = 0; k < 2; ++k) {
      const int b = s.body[k];
      if (b < 0) continue;
      const Vec3 force = (k == 1 ? 1 : -1) * f * s.scale * s.unit;  // (f < 0, a pull, draws the ends together)
      const Vec3 torque = (s.point[k] - com_in(model, body_q, b)).cross(force);
      Scalar* w = body_f + 6 * static_cast<size_t>(b);
      for (int m = 0; m < 3; ++m) w[m] += force[m], w[3 + m] += torque[m];
    }
}

void set_spatial_rest_lengths(Model& model) {
  bool any = false;
  for (int t = 0; t < model.tendon_count; ++t) any |= is_spatial(model, t) && std::isnan(model.tendon_rest_length[t]);
  if (!any) return;
  const State q0 = model.state();
  std::vector<TendonSpan> spans;
  for (int t = 0; t < model.tendon_count; ++t)
    if (is_spatial(model, t) && std::isnan(model.tendon_rest_length[t]))
      model.tendon_rest_length[t] = spatial_tendon(model, t, q0.body_q.data(), spans);
}

}  // namespace novaphy
