#include "kernels/fk.h"

namespace novaphy {

void forward_kinematics(const ArticulationView& art, const Scalar* q, ArticulationScratch& s) {
  for (int i = 0; i < art.link_count(); ++i) {
    const JointType type = art.type(i);
    const int p = art.parent(i);
    const Transform X_c = art.X_c(i);

    // pose of the link in its parent: X_p * J(q) * X_c^-1
    s.X_up[i] = art.X_p(i) * joint_motion(type, art.axis(i), q + art.q_start(i)) * X_c.inverse();
    s.X_world[i] = p < 0 ? s.X_up[i] : s.X_world[p] * s.X_up[i];
    s.Xup[i] = motion_xform(s.X_up[i]);
    s.I[i] = art.inertia(i);

    // motion subspace, child joint frame -> link frame
    const int d = art.dof(i);
    if (d == 0) continue;
    auto S_i = s.S.middleCols(art.qd_start(i), d);
    joint_subspace(type, art.axis(i), q + art.q_start(i), S_i);
    S_i = motion_xform(X_c.inverse()) * S_i;
  }
}

void forward_velocity(const ArticulationView& art, const Scalar* qd, ArticulationScratch& s) {
  for (int i = 0; i < art.link_count(); ++i) {
    const int p = art.parent(i);
    const int d = art.dof(i);
    const Vec6 v_J = s.S.middleCols(art.qd_start(i), d) * Eigen::Map<const VecX>(qd + art.qd_start(i), d);
    s.v[i] = p < 0 ? v_J : Vec6(s.Xup[i] * s.v[p] + v_J);
    s.c[i] = crm(s.v[i]) * v_J;
    if (joint_is_six_dof(art.type(i))) {
      const Transform X_c = art.X_c(i);
      const Vec6 c_J = joint_bias_acceleration(art.type(i), motion_xform(X_c) * v_J);
      s.c[i] += motion_xform(X_c.inverse()) * c_J;
    }
  }
}

}  // namespace novaphy
