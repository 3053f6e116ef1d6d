// What a kernel sees of one articulation: read-only pointers into the model's flat arrays,
// and the per-articulation scratch the kernels fill (Pinocchio's Model/Data split).
// Joint j of the model in [joint_begin, joint_end) is link (j - joint_begin) of the articulation;
// its child body carries the link's inertia. Links are ordered parents first.
#pragma once

#include <vector>

#include "kernels/joint.h"

namespace novaphy {

struct ArticulationView {
  int joint_begin = 0;
  int joint_end = 0;
  const int* joint_type = nullptr;          // [joint]
  const int* joint_ancestor = nullptr;      // [joint] parent joint (model index), -1 for the world
  const int* joint_child = nullptr;         // [joint] child body
  const int* joint_q_start = nullptr;       // [joint + 1]
  const int* joint_qd_start = nullptr;      // [joint + 1]
  const Scalar* joint_X_p = nullptr;        // [joint][7] parent link -> parent joint frame
  const Scalar* joint_X_c = nullptr;        // [joint][7] child link -> child joint frame
  const Scalar* joint_axis = nullptr;       // [joint][3]
  const Scalar* joint_armature = nullptr;   // [dof]
  const Scalar* joint_damping = nullptr;    // [dof]
  const Scalar* joint_stiffness = nullptr;  // [dof]
  const Scalar* joint_q_ref = nullptr;      // [coord]
  const Scalar* body_mass = nullptr;        // [body]
  const Scalar* body_com = nullptr;         // [body][3]
  const Scalar* body_inertia = nullptr;     // [body][9] about the centre of mass, body frame
  const Scalar* world_gravity = nullptr;    // [3] its world's gravity

  int link_count() const { return joint_end - joint_begin; }
  int q_begin() const { return joint_q_start[joint_begin]; }
  int qd_begin() const { return joint_qd_start[joint_begin]; }
  int coord_count() const { return joint_q_start[joint_end] - q_begin(); }
  int dof_count() const { return joint_qd_start[joint_end] - qd_begin(); }

  // per-link accessors in local numbering
  JointType type(int i) const { return static_cast<JointType>(joint_type[joint_begin + i]); }
  int parent(int i) const {
    const int a = joint_ancestor[joint_begin + i];
    return a < 0 ? -1 : a - joint_begin;
  }
  int q_start(int i) const { return joint_q_start[joint_begin + i] - q_begin(); }
  int qd_start(int i) const { return joint_qd_start[joint_begin + i] - qd_begin(); }
  int dof(int i) const { return joint_qd_start[joint_begin + i + 1] - joint_qd_start[joint_begin + i]; }
  Transform X_p(int i) const { return Transform::from_array(joint_X_p + 7 * (joint_begin + i)); }
  Transform X_c(int i) const { return Transform::from_array(joint_X_c + 7 * (joint_begin + i)); }
  Vec3 axis(int i) const { return Eigen::Map<const Vec3>(joint_axis + 3 * (joint_begin + i)); }
  int body(int i) const { return joint_child[joint_begin + i]; }
  Vec3 gravity() const { return Eigen::Map<const Vec3>(world_gravity); }
  Vec3 com(int i) const { return Eigen::Map<const Vec3>(body_com + 3 * body(i)); }
  Mat6 inertia(int i) const {
    const int b = body(i);
    const Mat3 I_c = Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(body_inertia + 9 * b);
    return spatial_inertia(body_mass[b], com(i), I_c);
  }
};

// per-articulation scratch: sized once by resize() (H and link_jacobian by their kernels), reused by
// every kernel call
struct ArticulationScratch {
  std::vector<Transform> X_up;     // pose of link i in its parent link (world for a root)
  std::vector<Transform> X_world;  // pose of link i in the world
  std::vector<Mat6> Xup;           // Plücker transform parent -> link i
  MatX S;                          // 6 x dof motion subspace in link coordinates
  std::vector<Vec6> c;             // velocity-product acceleration c_J + v x v_J (link coordinates)
  std::vector<Vec6> v, a, f;       // link velocity, acceleration, force (link coordinates)
  std::vector<Mat6> I;             // link spatial inertia (link coordinates)
  std::vector<Mat6> IC;            // composite inertia (CRBA), articulated inertia (ABA)
  std::vector<Vec6> pA;            // articulated bias force (ABA)
  MatX U;                          // 6 x dof, IA S (ABA)
  std::vector<Mat6> D_inv;         // inverse of S^T IA S, top-left dof x dof block (ABA)
  // sized by their kernels on first use (O(n^2) memory, which an articulation on ABA never pays)
  MatX H;  // joint-space inertia, then its Cholesky factor (crba)
  std::vector<Eigen::Matrix<Scalar, 6, Eigen::Dynamic>> link_jacobian;  // 6 x dof per link (mass_matrix_gemm)
  MatX S_world;                                                         // 6 x dof motion subspace in world coordinates
  VecX u;                                                               // dof work vector
  VecX qd_step, qdd_zero, tau_step;                                     // dof work vectors of bias_velocity_jacobian
  MatX C;  // d bias / d qd (bias_velocity_jacobian, sized there)

  void resize(const ArticulationView& art);
};

}  // namespace novaphy
