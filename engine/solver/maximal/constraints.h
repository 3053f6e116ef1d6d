// What the solvers in maximal coordinates (SolverSemiImplicit, SolverXPBD) hold between bodies, built once for the
// model: every joint and Connect or Weld equality as a constraint between two bodies' frames, each of whose six axes
// (angular x, y, z, then linear x, y, z of the constraint frame) is free, locked or limited, some driven; and the
// per-step view of the bodies they act on (BodyMotion). joint_q and joint_qd follow from the bodies
// (joint_coordinates), the inverse of forward kinematics.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

enum class AxisMode : std::uint8_t { Free = 0, Locked = 1, Limited = 2 };

// a constraint between body a's frame X_a and body b's frame X_b (each in its body's frame; body -1: the world);
// axis k of the constraint frame (a's frame): 0..2 angular, 3..5 linear. Its coordinates on those axes are the
// rotation vector of b's frame in a's (angular) and b's frame origin in a's (linear), a distance constraint's the
// origins' distance (axis 3 only)
struct MaximalConstraint {
  int joint = -1;     // the model's joint, or -1: an equality
  int equality = -1;  // the model's equality, or -1
  int world = 0;
  int a = -1, b = -1;
  Transform X_a, X_b;
  bool distance = false;
  AxisMode mode[6] = {};
  Scalar lower[6] = {}, upper[6] = {};
  int dof[6] = {-1, -1, -1, -1, -1, -1};  // the model's dof on that axis (drives, damping, springs), -1: none
  Scalar compliance[2] = {};              // linear, angular (0: rigid)
};

// the constraints of a model by world (constraints [world_start[w], world_start[w + 1]) are world w's), each world's
// bodies and joints in order (world_bodies from body_start[w], world_joints from joint_start[w]), the bodies that do
// not move (held to the world by Fixed joints, directly or through others), and for each moving body of no mass (an
// MJCF body of several joints is a chain whose inner links have none) the body whose mass and inertia it takes a
// share of (kStandInShare): the nearest one of mass below it along its chain
struct MaximalConstraints {
  static constexpr Scalar kStandInShare = 0.01;
  std::vector<MaximalConstraint> constraints;
  std::vector<int> world_start;
  std::vector<int> world_bodies, body_start;
  std::vector<int> world_joints, joint_start;
  std::vector<std::uint8_t> body_static;
  std::vector<int> stand_in_of;  // per body: -1, or the body of mass it stands in for

  // fails naming the first element `solver` does not model: a JointCoupling equality, a fixed tendon, a sensor, a
  // moving body of no mass with none of mass below it
  static MaximalConstraints of(const Model& model, const std::string& solver);
  // joint_q and joint_qd of world w's joints from its bodies' body_q and body_qd (the inverse of forward
  // kinematics; a Revolute angle and a quaternion's sign continue from the coordinates the state holds)
  void joint_coordinates(const Model& model, State& state, int w) const;
};

// the rotation vector (angle times axis, angle in [0, pi]) of the unit quaternion q
Vec3 rotation_vector(const Quat& q);
// q turned by the rotation vector r (world frame), renormalised: exp(r) q
Quat turned(const Quat& q, const Vec3& r);
// the same to first order in r, renormalised, (1 + r / 2) q: XPBD's update of an orientation by a correction or a
// substep's turn (no trigonometry)
Quat turned_slightly(const Quat& q, const Vec3& r);

// a body as a step of the maximal solvers sees it: its centre of mass x, orientation q, COM velocity v and angular
// velocity w (world), inverse mass and inverse inertia (in its frame and in the world; 0 for the world and static
// bodies)
struct BodyMotion {
  Vec3 x = Vec3::Zero();
  Quat q = Quat::Identity();
  Vec3 v = Vec3::Zero(), w = Vec3::Zero();
  Scalar inv_mass = 0;
  Mat3 inv_inertia_body = Mat3::Zero(), inv_inertia = Mat3::Zero();

  // body b's pose and velocity in the state (b = -1: the world, at rest), no mass
  static BodyMotion of(const Model& model, const State& state, int b);
  // the world inverse inertia again at the orientation q
  void orient() {
    const Mat3 R = q.toRotationMatrix();
    inv_inertia = R * inv_inertia_body * R.transpose();
  }
  // the velocity of the world point p riding on the body
  Vec3 point_velocity(const Vec3& p) const { return v + w.cross(p - x); }
  // the body's frame (its origin's pose) from x and q
  Transform frame(const Model& model, int b) const;
  // written into body_q and body_qd of b
  void store(const Model& model, int b, State& state) const;
};

// a constraint frame X on body b (its frame) in the world, from the body's motion
inline Transform constraint_frame(const Model& model, const BodyMotion& body, int b, const Transform& X) {
  return b < 0 ? X : body.frame(model, b) * X;
}

// a constraint's six coordinates (axis k as MaximalConstraint says) from its frames in the world
void constraint_coordinates(const MaximalConstraint& c, const Transform& frame_a, const Transform& frame_b,
                            Scalar coordinate[6]);

}  // namespace novaphy
