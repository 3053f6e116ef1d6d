// The seed's free functions on one articulation given as lists: joints[i] attaches link i,
// described by bodies[i], to link joints[i].parent (-1: the world). Each builds a Model through
// ModelBuilder (so every argument is checked the same way) and calls engine/eval/eval; forward_dynamics keeps
// the last articulation's model and its ForwardDynamics (the step's batched kernels) per thread, so calls
// about the same joints and bodies set nothing up again.
#pragma once

#include <vector>

#include "engine/model/builder.h"

namespace novaphy {

struct Joint {
  JointType type = JointType::Revolute;
  Vec3 axis = Vec3(1, 0, 0);
  int parent = -1;            // link index, -1 for the world
  Transform parent_to_joint;  // parent link frame -> joint frame (child link frame at q = 0)
};

Model articulation_model(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies,
                         const Vec3& gravity = Vec3::Zero());

// world transforms [px, py, pz, qx, qy, qz, qw] of every link, one row each
Eigen::Matrix<Scalar, Eigen::Dynamic, 7, Eigen::RowMajor> forward_kinematics(const std::vector<Joint>& joints,
                                                                             const VecX& q);
VecX inverse_dynamics(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q,
                      const VecX& qd, const VecX& qdd, const Vec3& gravity);
MatX mass_matrix_crba(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q);
VecX forward_dynamics(const std::vector<Joint>& joints, const std::vector<RigidBody>& bodies, const VecX& q,
                      const VecX& qd, const VecX& tau, const Vec3& gravity);

}  // namespace novaphy
