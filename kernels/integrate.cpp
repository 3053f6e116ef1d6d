#include "kernels/integrate.h"

namespace novaphy {

namespace {

Quat exp_map(const Vec3& rotation) {
  const Scalar angle = rotation.norm();
  if (angle < 1e-12) return Quat(1, 0.5 * rotation.x(), 0.5 * rotation.y(), 0.5 * rotation.z()).normalized();
  return Quat(Eigen::AngleAxis<Scalar>(angle, rotation / angle));
}

void store(const Quat& r, Scalar* q) {
  const Quat n = r.normalized();
  q[0] = n.x(), q[1] = n.y(), q[2] = n.z(), q[3] = n.w();
}

}  // namespace

void integrate_joints(const ArticulationView& art, const Scalar* q, const Scalar* qd, Scalar dt, Scalar* q_out) {
  for (int i = 0; i < art.link_count(); ++i) {
    const Scalar* x = q + art.q_start(i);
    const Scalar* v = qd + art.qd_start(i);
    Scalar* y = q_out + art.q_start(i);
    switch (art.type(i)) {
      case JointType::Revolute:
      case JointType::Prismatic: y[0] = x[0] + dt * v[0]; break;
      case JointType::Ball: store(joint_quat(x) * exp_map(dt * Vec3(v[0], v[1], v[2])), y); break;
      case JointType::Free:
      case JointType::Distance:
      case JointType::D6:
      case JointType::Cable:
        for (int k = 0; k < 3; ++k) y[k] = x[k] + dt * v[3 + k];
        store(exp_map(dt * Vec3(v[0], v[1], v[2])) * joint_quat(x + 3), y + 3);
        break;
      case JointType::Fixed: break;
    }
  }
}

}  // namespace novaphy
