// Spatial algebra in Featherstone's conventions (RBDA, chapter 2).
// motion vectors are [angular; linear], force vectors are [torque; force].
// a Transform is a pose: x_parent = R * x_child + p, quaternion stored [x, y, z, w].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace novaphy {

using Scalar = double;
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
using Vec6 = Eigen::Matrix<Scalar, 6, 1>;
using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
using Mat6 = Eigen::Matrix<Scalar, 6, 6>;
using MatX = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
using VecX = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
using Quat = Eigen::Quaternion<Scalar>;

struct Transform {
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();

  static Transform identity() { return {}; }
  static Transform from_array(const Scalar* x) {  // [px, py, pz, qx, qy, qz, qw]
    Transform t;
    t.p = Vec3(x[0], x[1], x[2]);
    t.q = Quat(x[6], x[3], x[4], x[5]);
    return t;
  }
  void to_array(Scalar* x) const {
    x[0] = p.x(), x[1] = p.y(), x[2] = p.z();
    x[3] = q.x(), x[4] = q.y(), x[5] = q.z(), x[6] = q.w();
  }
  Mat3 rotation() const { return q.toRotationMatrix(); }
  Vec3 apply(const Vec3& x) const { return q * x + p; }
  Transform inverse() const {
    Transform t;
    t.q = q.conjugate();
    t.p = -(t.q * p);
    return t;
  }
  Transform operator*(const Transform& b) const {
    Transform t;
    t.q = q * b.q;
    t.p = q * b.p + p;
    return t;
  }
};

inline Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Plücker transform taking motion vectors from parent coordinates to the coordinates of a
// child frame whose pose in the parent is T (Featherstone's X = [E 0; -E rx E], E = R^T, r = p).
inline Mat6 motion_xform(const Transform& T) {
  const Mat3 E = T.rotation().transpose();
  Mat6 X;
  X.topLeftCorner<3, 3>() = E;
  X.topRightCorner<3, 3>().setZero();
  X.bottomLeftCorner<3, 3>() = -E * skew(T.p);
  X.bottomRightCorner<3, 3>() = E;
  return X;
}

// motion cross product v x m, and its force dual v x* f
inline Mat6 crm(const Vec6& v) {
  Mat6 m = Mat6::Zero();
  m.topLeftCorner<3, 3>() = skew(v.head<3>());
  m.bottomLeftCorner<3, 3>() = skew(v.tail<3>());
  m.bottomRightCorner<3, 3>() = skew(v.head<3>());
  return m;
}
inline Mat6 crf(const Vec6& v) { return -crm(v).transpose(); }

// spatial inertia about the frame origin of a body with mass m, centre of mass c and
// rotational inertia I_c about the centre of mass (all in that frame)
inline Mat6 spatial_inertia(Scalar m, const Vec3& c, const Mat3& I_c) {
  const Mat3 C = skew(c);
  Mat6 I;
  I.topLeftCorner<3, 3>() = I_c + m * C * C.transpose();
  I.topRightCorner<3, 3>() = m * C;
  I.bottomLeftCorner<3, 3>() = m * C.transpose();
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
  return I;
}

}  // namespace novaphy
