#include "engine/model/weld.h"

namespace novaphy {

namespace {

// inertia about the centre of mass, in the link frame, of a body whose pose in the link is T
struct MassProperties {
  Scalar mass = 0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
};

MassProperties body_in_link(const Model& model, int b, const Transform& T) {
  MassProperties m;
  m.mass = model.body_mass[b];
  m.com = T.apply(Eigen::Map<const Vec3>(&model.body_com[3 * b]));
  const Mat3 R = T.rotation();
  m.inertia =
      R * Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(&model.body_inertia[9 * b]) * R.transpose();
  return m;
}

// the two bodies as one rigid body (parallel axis theorem about the joint centre of mass)
MassProperties combine(const MassProperties& a, const MassProperties& b) {
  MassProperties c;
  c.mass = a.mass + b.mass;
  c.com = c.mass > 0 ? ((a.mass * a.com + b.mass * b.com) / c.mass).eval() : a.com;
  auto shifted = [&](const MassProperties& m) {
    const Vec3 d = m.com - c.com;
    return (m.inertia + m.mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose())).eval();
  };
  c.inertia = shifted(a) + shifted(b);
  return c;
}

}  // namespace

void weld_masses(const Model& model, WeldedModel& w, const std::vector<std::uint8_t>& worlds) {
  auto merge = [&](int b) { return worlds.empty() || worlds[model.body_world[b]] != 0; };
  std::vector<MassProperties> merged(model.body_count);
  for (int b = 0; b < model.body_count; ++b)
    if (merge(b)) merged[b] = body_in_link(model, b, Transform::identity());
  for (const int child : w.welded_bodies) {  // (in the order of their joints)
    if (!merge(child)) continue;
    const int link = w.link_body[child];
    merged[link] = combine(merged[link], body_in_link(model, child, w.offset[child]));
    merged[child] = MassProperties{};
  }
  Model& m = w.model;
  for (int b = 0; b < model.body_count; ++b) {
    if (!merge(b)) continue;
    m.body_mass[b] = merged[b].mass;
    Eigen::Map<Vec3>(&m.body_com[3 * b]) = merged[b].com;
    Eigen::Map<Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(&m.body_inertia[9 * b]) = merged[b].inertia;
  }
}

WeldedModel weld_fixed_joints(const Model& model, bool weld) {
  WeldedModel w;
  w.link_body.resize(model.body_count);
  for (int b = 0; b < model.body_count; ++b) w.link_body[b] = b;
  w.offset.assign(model.body_count, Transform::identity());
  bool any = false;
  for (int j = 0; j < model.joint_count && weld; ++j)
    any |= static_cast<JointType>(model.joint_type[j]) == JointType::Fixed && model.joint_parent[j] >= 0;
  if (!any) return w;
  w.model = model;
  Model& m = w.model;

  std::vector<int> kept, new_index(model.joint_count, -1);
  std::vector<Transform> X_p(model.joint_count);
  for (int j = 0; j < model.joint_count; ++j) {
    const int parent = model.joint_parent[j], child = model.joint_child[j];
    X_p[j] = Transform::from_array(&model.joint_X_p[7 * j]);
    if (parent >= 0) X_p[j] = w.offset[parent] * X_p[j];  // the joint frame in the parent's link
    if (weld && static_cast<JointType>(model.joint_type[j]) == JointType::Fixed && parent >= 0) {
      const int link = w.link_body[parent];
      w.link_body[child] = link;
      w.offset[child] = X_p[j] * Transform::from_array(&model.joint_X_c[7 * j]).inverse();
      w.welded_bodies.push_back(child);
      continue;
    }
    new_index[j] = static_cast<int>(kept.size());
    kept.push_back(j);
  }

  weld_masses(model, w, {});
  std::vector<int> body_joint(model.body_count, -1);
  for (const int j : kept) body_joint[model.joint_child[j]] = new_index[j];
  m.joint_count = static_cast<int>(kept.size());
  m.joint_type.clear(), m.joint_parent.clear(), m.joint_child.clear(), m.joint_ancestor.clear();
  m.joint_articulation.clear(), m.joint_q_start.clear(), m.joint_qd_start.clear();
  m.joint_X_p.clear(), m.joint_X_c.clear(), m.joint_axis.clear(), m.joint_compliance.clear(), m.joint_name.clear();
  for (const int j : kept) {
    const int parent = model.joint_parent[j] < 0 ? -1 : w.link_body[model.joint_parent[j]];
    m.joint_type.push_back(model.joint_type[j]);
    m.joint_parent.push_back(parent);
    m.joint_child.push_back(model.joint_child[j]);
    m.joint_ancestor.push_back(parent < 0 ? -1 : body_joint[parent]);
    m.joint_articulation.push_back(model.joint_articulation[j]);
    m.joint_q_start.push_back(model.joint_q_start[j]);
    m.joint_qd_start.push_back(model.joint_qd_start[j]);
    X_p[j].to_array(&*m.joint_X_p.insert(m.joint_X_p.end(), 7, 0));
    m.joint_X_c.insert(m.joint_X_c.end(), &model.joint_X_c[7 * j], &model.joint_X_c[7 * j] + 7);
    m.joint_axis.insert(m.joint_axis.end(), &model.joint_axis[3 * j], &model.joint_axis[3 * j] + 3);
    m.joint_compliance.insert(m.joint_compliance.end(), &model.joint_compliance[2 * j],
                              &model.joint_compliance[2 * j] + 2);
    if (!model.joint_name.empty()) m.joint_name.push_back(model.joint_name[j]);
  }
  m.joint_q_start.push_back(model.joint_q_start[model.joint_count]);
  m.joint_qd_start.push_back(model.joint_qd_start[model.joint_count]);
  // articulations are runs of joints whose roots are never welded: count the kept joints before each
  for (int a = 0, start = 0; a <= model.articulation_count; ++a) {
    while (start < m.joint_count && kept[start] < model.articulation_start[a]) ++start;
    m.articulation_start[a] = start;
  }
  for (int& joint : m.actuator_joint)
    if (joint >= 0) joint = new_index[joint];
  for (int e = 0; e < m.equality_count; ++e)
    if (static_cast<EqualityType>(m.equality_type[e]) == EqualityType::JointCoupling)
      for (int k = 0; k < 2; ++k)
        if (m.equality_object[2 * e + k] >= 0) m.equality_object[2 * e + k] = new_index[m.equality_object[2 * e + k]];
  m.check_sizes();
  return w;
}

}  // namespace novaphy
