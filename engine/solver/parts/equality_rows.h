// The rows of an equality constraint (model.h: Connect, Weld, JointCoupling): bilateral rows (Bounded, no bound) that
// drive the constraint's error to zero, a share erp of it each step, or soft as MuJoCo's (soft_row.h) by its
// solref. The constraint's data read as named records (the model keeps them as equality_data[10 e ..]).
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "engine/model/model.h"
#include "engine/solver/parts/soft_row.h"
#include "engine/solver/parts/warm_start.h"
#include "kernels/pgs.h"

namespace novaphy {

// (warm start and kept impulse: KeptImpulseRow)
struct EqualityRow : KeptImpulseRow {
  static constexpr RowKind kKind = RowKind::Bounded;

  template <typename V, typename Settings>
  static V target(const V& error, const Settings& p, const V& dt) {
    return -static_cast<Element<V>>(p.erp) * error / dt;
  }
  static Scalar bound() { return std::numeric_limits<Scalar>::infinity(); }
  // a soft row's cfm and target: its error along the row, the constraint's whole error (the norm over its rows,
  // where MuJoCo reads the impedance), the row's velocity at the step's start
  static SoftRow soft(Scalar error, Scalar whole, Scalar v, const Softness& s, Scalar dt) {
    return soft_row(s.solref, s.solimp, s.weight, whole, error, v, dt);
  }
  // equality e's softness; its rows' weights (MuJoCo's): the two bodies' translational invweight0 for a Connect's
  // or Weld's position rows, their rotational one for a Weld's rotation rows, the two joints' dofs' for a coupling.
  // MuJoCo's weld rotation rows are half of these rows (half the relative angular velocity, the error's quaternion
  // part, soft_turn): such a row of ours with four times MuJoCo's cfm moves the bodies as MuJoCo's
  static Softness softness(const Model& model, int e, bool rotation) {
    const int o1 = model.equality_object[2 * e], o2 = model.equality_object[2 * e + 1];
    Scalar weight = 0;
    if (static_cast<EqualityType>(model.equality_type[e]) == EqualityType::JointCoupling) {
      for (const int j : {o1, o2})
        if (j >= 0) weight += model.joint_invweight0[model.joint_qd_start[j]];
    } else {
      for (const int b : {o1, o2})
        if (b >= 0) weight += model.body_invweight0[2 * b + (rotation ? 1 : 0)] * (rotation ? 4 : 1);
    }
    return softness_of(&model.equality_solref[2 * e], &model.equality_solimp[5 * e], weight);
  }
  // a soft weld's rotation error as its rows read it, from the rotation vector `turn` (errors()): twice MuJoCo's,
  // the quaternion's vector part sin(angle / 2) axis
  static Vec3 soft_turn(const Vec3& turn) {
    const Scalar angle = turn.norm();
    return angle > 0 ? Vec3(2 * std::sin(angle / 2) / angle * turn) : turn;
  }
  // its rows: a Weld's 6 (3 for the anchors' gap, 3 for the rotation), a Connect's 3, a JointCoupling's 1
  static int count(EqualityType type) { return type == EqualityType::Weld ? 6 : type == EqualityType::Connect ? 3 : 1; }
};

// a Connect's or Weld's data: the anchor on body 1 (in its frame) held on the anchor on body 2 (in its), and a
// weld's orientation of body 2 in body 1's frame
struct BodyEquality {
  Vec3 anchor1, anchor2;
  Quat relative;  // (a weld's)

  static BodyEquality of(const Model& model, int e) {
    const Scalar* data = &model.equality_data[10 * e];
    return {Vec3(data[0], data[1], data[2]), Vec3(data[3], data[4], data[5]), Quat(data[9], data[6], data[7], data[8])};
  }

  // at the bodies' poses X1, X2: the anchors' midpoint (where the translational rows act), their gap p2 - p1, and a
  // weld's rotation from body 2's held orientation to its own (angle times axis; turn null: a connect's none)
  void errors(const Transform& X1, const Transform& X2, Vec3* mid, Vec3* gap, Vec3* turn) const {
    const Vec3 p1 = X1.apply(anchor1), p2 = X2.apply(anchor2);
    *mid = (p1 + p2) / 2;
    *gap = p2 - p1;
    if (!turn) return;
    const Eigen::AngleAxis<Scalar> rotation(X2.q * (X1.q * relative).inverse());
    *turn = rotation.angle() * rotation.axis();
  }
};

// a JointCoupling's data: q1 - q1_ref = poly(x), x = q2 - q2_ref (poly: a0 + a1 x + .. + a4 x^4; q1_ref and q2_ref
// are model.h's q1_0 and q2_0)
struct JointCoupling {
  Scalar poly[5];
  Scalar q1_ref, q2_ref;

  static JointCoupling of(const Model& model, int e) {
    const Scalar* data = &model.equality_data[10 * e];
    return {{data[0], data[1], data[2], data[3], data[4]}, data[5], data[6]};
  }

  // its error q1 - q1_ref - poly(x) and the slope d poly / dx at x = q2 - q2_ref
  Scalar error(Scalar q1, Scalar q2, Scalar* slope) const {
    const Scalar* a = poly;
    const Scalar x = q2 - q2_ref;
    *slope = a[1] + x * (2 * a[2] + x * (3 * a[3] + x * 4 * a[4]));
    return q1 - q1_ref - (a[0] + x * (a[1] + x * (a[2] + x * (a[3] + x * a[4]))));
  }
};

}  // namespace novaphy
