#include "kernels/articulation.h"

namespace novaphy {

const char* joint_type_name(JointType type) {
  switch (type) {
    case JointType::Revolute: return "Revolute";
    case JointType::Prismatic: return "Prismatic";
    case JointType::Ball: return "Ball";
    case JointType::Fixed: return "Fixed";
    case JointType::Free: return "Free";
    case JointType::Distance: return "Distance";
    case JointType::D6: return "D6";
    case JointType::Cable: return "Cable";
  }
  return "Unknown";
}

void ArticulationScratch::resize(const ArticulationView& art) {
  const int n = art.link_count();
  const int nv = art.dof_count();
  X_up.resize(n);
  X_world.resize(n);
  Xup.resize(n);
  c.resize(n);
  v.resize(n);
  a.resize(n);
  f.resize(n);
  I.resize(n);
  IC.resize(n);
  pA.resize(n);
  D_inv.resize(n);
  S.setZero(6, nv);
  U.setZero(6, nv);
  u.setZero(nv);
  qd_step.setZero(nv);
  qdd_zero.setZero(nv);
  tau_step.setZero(nv);
  S_world.setZero(6, nv);
}

}  // namespace novaphy
