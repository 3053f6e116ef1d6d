// Joint models: coordinate counts, joint motion J(q), motion subspace S and c_J = dS/dt qd
// (Featherstone RBDA, section 4.4). Everything here is expressed in the joint's child frame.
#pragma once

#include "kernels/spatial.h"

namespace novaphy {

// Distance, D6 and Cable are maximal-coordinate joints (the solvers in maximal coordinates enforce them; Featherstone
// refuses them): kinematically each is a Free joint relative to its parent, q = the child joint frame's pose in the
// parent joint frame [px, py, pz, qx, qy, qz, qw], qd = [w; v] of it in the parent joint frame
enum class JointType : int {
  Revolute = 0,
  Prismatic = 1,
  Ball = 2,
  Fixed = 3,
  Free = 4,
  Distance = 5,
  D6 = 6,
  Cable = 7
};

// whether the joint's coordinates are a pose and its velocity a twist (Free and the maximal-coordinate joints)
constexpr bool joint_is_six_dof(JointType type) {
  return type == JointType::Free || type == JointType::Distance || type == JointType::D6 || type == JointType::Cable;
}

constexpr int joint_coord_count(JointType type) {
  switch (type) {
    case JointType::Revolute:
    case JointType::Prismatic: return 1;
    case JointType::Ball: return 4;
    case JointType::Fixed: return 0;
    case JointType::Free:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable: return 7;
  }
  return 0;
}

constexpr int joint_dof_count(JointType type) {
  switch (type) {
    case JointType::Revolute:
    case JointType::Prismatic: return 1;
    case JointType::Ball: return 3;
    case JointType::Fixed: return 0;
    case JointType::Free:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable: return 6;
  }
  return 0;
}

const char* joint_type_name(JointType type);

// unit quaternion from stored [x, y, z, w] coordinates (normalised, as MuJoCo does in kinematics)
inline Quat joint_quat(const Scalar* q) { return Quat(q[3], q[0], q[1], q[2]).normalized(); }

// pose of the child joint frame in the parent joint frame
inline Transform joint_motion(JointType type, const Vec3& axis, const Scalar* q) {
  Transform J;
  switch (type) {
    case JointType::Revolute: J.q = Quat(Eigen::AngleAxis<Scalar>(q[0], axis)); break;
    case JointType::Prismatic: J.p = q[0] * axis; break;
    case JointType::Ball: J.q = joint_quat(q); break;
    case JointType::Free:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable:
      J.p = Vec3(q[0], q[1], q[2]);
      J.q = joint_quat(q + 3);
      break;
    case JointType::Fixed: break;
  }
  return J;
}

// motion subspace S (6 x dof, child joint frame)
//   Free: qd = [w; v] in the parent joint frame, so S = diag(R^T, R^T)
template <typename SMat>
inline void joint_subspace(JointType type, const Vec3& axis, const Scalar* q, SMat&& S) {
  switch (type) {
    case JointType::Revolute: S.col(0) << axis, Vec3::Zero(); break;
    case JointType::Prismatic: S.col(0) << Vec3::Zero(), axis; break;
    case JointType::Ball:
      S.setZero();
      S.template topLeftCorner<3, 3>().setIdentity();
      break;
    case JointType::Free:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable: {
      const Mat3 Rt = joint_quat(q + 3).toRotationMatrix().transpose();
      S.setZero();
      S.template topLeftCorner<3, 3>() = Rt;
      S.template bottomRightCorner<3, 3>() = Rt;
      break;
    }
    case JointType::Fixed: break;
  }
}

// c_J = (dS/dt) qd in the child joint frame, from the joint velocity v_J = S qd (same frame):
// only a six-dof joint has a moving subspace, d(R^T)/dt = -[R^T w]x R^T gives c_J = [0; -w_J x v_J]
inline Vec6 joint_bias_acceleration(JointType type, const Vec6& v_J) {
  Vec6 c_J = Vec6::Zero();
  if (joint_is_six_dof(type)) c_J.tail<3>() = -v_J.head<3>().cross(v_J.tail<3>());
  return c_J;
}

}  // namespace novaphy
