#include "engine/solver/maximal/corrections.h"

#include <algorithm>

namespace novaphy {

namespace {

constexpr Scalar kTiny = 1e-12;

}  // namespace

Scalar inverse_mass(const std::vector<BodyMotion>& bodies, int i, const Vec3& p, const Vec3& n) {
  if (i < 0) return 0;
  const BodyMotion& m = bodies[i];
  if (m.inv_mass == 0) return 0;
  const Vec3 rn = (p - m.x).cross(n);
  return m.inv_mass + rn.dot(m.inv_inertia * rn);
}

void apply_impulse(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb, const Vec3& p) {
  if (b >= 0 && bodies[b].inv_mass > 0) {
    BodyMotion& B = bodies[b];
    B.v += B.inv_mass * p;
    B.w += B.inv_inertia * (pb - B.x).cross(p);
  }
  if (a >= 0 && bodies[a].inv_mass > 0) {
    BodyMotion& A = bodies[a];
    A.v -= A.inv_mass * p;
    A.w -= A.inv_inertia * (pa - A.x).cross(p);
  }
}

Scalar push(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb, const Vec3& n, Scalar C,
            Scalar alpha_h, Scalar* lambda, Scalar relaxation) {
  const Scalar w = inverse_mass(bodies, a, pa, n) + inverse_mass(bodies, b, pb, n);
  if (w + alpha_h < kTiny) return 0;
  const Scalar change = (-C - alpha_h * *lambda) / (w + alpha_h);
  *lambda += change;
  const Vec3 p = (relaxation * change) * n;
  if (b >= 0 && bodies[b].inv_mass > 0) {
    BodyMotion& B = bodies[b];
    B.x += B.inv_mass * p;
    B.q = turned_slightly(B.q, B.inv_inertia * (pb - B.x).cross(p));
    B.orient();
  }
  if (a >= 0 && bodies[a].inv_mass > 0) {
    BodyMotion& A = bodies[a];
    A.x -= A.inv_mass * p;
    A.q = turned_slightly(A.q, -(A.inv_inertia * (pa - A.x).cross(p)));
    A.orient();
  }
  return change;
}

void turn(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& n, Scalar C, Scalar alpha_h, Scalar* lambda,
          Scalar relaxation) {
  Scalar w = 0;
  if (a >= 0) w += n.dot(bodies[a].inv_inertia * n);
  if (b >= 0) w += n.dot(bodies[b].inv_inertia * n);
  if (w + alpha_h < kTiny) return;
  const Scalar change = (-C - alpha_h * *lambda) / (w + alpha_h);
  *lambda += change;
  const Vec3 p = (relaxation * change) * n;
  if (b >= 0 && bodies[b].inv_mass > 0) {
    BodyMotion& B = bodies[b];
    B.q = turned_slightly(B.q, B.inv_inertia * p);
    B.orient();
  }
  if (a >= 0 && bodies[a].inv_mass > 0) {
    BodyMotion& A = bodies[a];
    A.q = turned_slightly(A.q, -(A.inv_inertia * p));
    A.orient();
  }
}

Scalar correct_position(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb,
                        const Vec3& correction, Scalar alpha_h, Scalar* lambda, Scalar relaxation) {
  const Scalar c = correction.norm();
  return c < kTiny ? 0 : push(bodies, a, b, pa, pb, correction / c, -c, alpha_h, lambda, relaxation);
}

void correct_rotation(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& correction, Scalar alpha_h,
                      Scalar* lambda, Scalar relaxation) {
  const Scalar c = correction.norm();
  if (c >= kTiny) turn(bodies, a, b, correction / c, -c, alpha_h, lambda, relaxation);
}

void hold_constraint(const Model& model, const MaximalConstraint& c, int a, int b, const HoldSettings& hold,
                     Scalar* lambda, std::vector<BodyMotion>& bodies) {
  auto frames = [&](Transform& frame_a, Transform& frame_b) {
    frame_a = a >= 0 ? bodies[a].frame(model, c.a) * c.X_a : c.X_a;
    frame_b = b >= 0 ? bodies[b].frame(model, c.b) * c.X_b : c.X_b;
  };
  Transform frame_a, frame_b;
  frames(frame_a, frame_b);
  if (c.distance) {
    const Vec3 gap = frame_b.p - frame_a.p;
    const Scalar length = gap.norm();
    if (length < kTiny) return;
    const Scalar held = std::clamp(length, c.lower[3], c.upper[3]);
    push(bodies, a, b, frame_a.p, frame_b.p, gap / length, length - held, hold.alpha_linear, &lambda[1],
         hold.relax_linear);
    return;
  }
  Scalar coordinate[6];
  constraint_coordinates(c, frame_a, frame_b, coordinate);
  // an axis's error: how far its coordinate is past what the axis allows
  auto error = [&](int k) {
    switch (c.mode[k]) {
      case AxisMode::Free: return Scalar(0);
      case AxisMode::Locked: return coordinate[k] - c.lower[k];
      case AxisMode::Limited: return coordinate[k] - std::clamp(coordinate[k], c.lower[k], c.upper[k]);
    }
    return Scalar(0);
  };
  const Vec3 turn_error(error(0), error(1), error(2));
  if (!turn_error.isZero()) {
    correct_rotation(bodies, a, b, -(frame_a.q * turn_error), hold.alpha_angular, &lambda[0], hold.relax_angular);
    frames(frame_a, frame_b);
    constraint_coordinates(c, frame_a, frame_b, coordinate);
  }
  const Vec3 offset_error(error(3), error(4), error(5));
  if (!offset_error.isZero())
    correct_position(bodies, a, b, frame_a.p, frame_b.p, -(frame_a.q * offset_error), hold.alpha_linear, &lambda[1],
                     hold.relax_linear);
}

}  // namespace novaphy
