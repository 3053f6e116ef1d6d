#include "engine/model/body_kinematics.h"

#include <algorithm>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/model/spatial_tendon.h"
#include "kernels/aba.h"
#include "kernels/fk.h"
#include "kernels/osim.h"

namespace novaphy {

namespace {

// the bytes that decide an articulation's body_invweight0 (joint_q0's FK, the articulated-body factor and
// osim_inverse) into key: per link its joint's type, parent and frames, axis, q0, armature and its body's mass, COM
// and inertia; not a root's parent frame nor a root Free joint's position, which only place the articulation in the
// world: neither enters a root's S or articulated inertia, and osim_inverse reads no transform above a root (so
// replicas placed apart share one key, their weights the same bits)
void invweight0_key(const Model& model, const ArticulationView& art, std::string& key) {
  key.clear();
  auto put = [&](const auto* x, int count) { key.append(reinterpret_cast<const char*>(x), sizeof(*x) * count); };
  for (int i = 0; i < art.link_count(); ++i) {
    const int j = art.joint_begin + i, b = art.body(i), parent = art.parent(i);
    const int skip = parent < 0 && art.type(i) == JointType::Free ? 3 : 0;  // (a root Free joint's position)
    put(&model.joint_type[j], 1);
    put(&parent, 1);
    if (parent >= 0) put(&model.joint_X_p[7 * j], 7);
    put(&model.joint_X_c[7 * j], 7);
    put(&model.joint_axis[3 * j], 3);
    put(model.joint_q0.data() + model.joint_q_start[j] + skip, joint_coord_count(art.type(i)) - skip);
    put(model.joint_armature.data() + model.joint_qd_start[j], art.dof(i));
    put(&model.body_mass[b], 1);
    put(&model.body_com[3 * b], 3);
    put(&model.body_inertia[9 * b], 9);
  }
}

}  // namespace

void store_body(const ArticulationScratch& s, int link, const Transform& offset, const Vec3& com, int b, State& state) {
  const Transform& X = s.X_world[link];
  (X * offset).to_array(state.body_q.data() + 7 * b);
  // body_qd = [velocity of the centre of mass; angular velocity], world frame
  const Vec3 w = s.v[link].head<3>();
  const Vec3 v_com = s.v[link].tail<3>() + w.cross(offset.apply(com));
  const Mat3 R = X.rotation();
  Eigen::Map<Vec6>(state.body_qd.data() + 6 * b) << R * v_com, R * w;
}

void store_body_state(const ArticulationView& art, const ArticulationScratch& s, State& state) {
  for (int i = 0; i < art.link_count(); ++i) store_body(s, i, Transform::identity(), art.com(i), art.body(i), state);
}

ArticulationView kinematics(const Model& model, const State& state, int a, ArticulationScratch& s) {
  const ArticulationView art = model.articulation(a);
  s.resize(art);
  forward_kinematics(art, state.joint_q.data() + art.q_begin(), s);
  forward_velocity(art, state.joint_qd.data() + art.qd_begin(), s);
  return art;
}

void bodies_from_joints(const Model& model, State& state) {
  ArticulationScratch s;
  for (int a = 0; a < model.articulation_count; ++a) store_body_state(kinematics(model, state, a, s), s, state);
}

namespace {

// whether a soft row weighs a dof or a tendon by its invweight0: a dof's or a tendon's limit or dry friction,
// a joint coupling (whose weight is its joints' dofs')
bool weighs_joints(const Model& model) {
  const auto is_soft = [](const Scalar* solref) { return solref[0] != 0 || solref[1] != 0; };  // (soft_row.h)
  for (int k = 0; k < model.joint_dof_count; ++k)
    if (is_soft(&model.joint_limit_solref[2 * k]) || is_soft(&model.joint_friction_solref[2 * k])) return true;
  for (int t = 0; t < model.tendon_count; ++t)
    if (is_soft(&model.tendon_limit_solref[2 * t]) || is_soft(&model.tendon_friction_solref[2 * t])) return true;
  for (int e = 0; e < model.equality_count; ++e)
    if (model.equality_type[e] == static_cast<int>(EqualityType::JointCoupling) &&
        is_soft(&model.equality_solref[2 * e]))
      return true;
  return false;
}

// art's dofs' invweight0, with s holding its articulated-body factor at joint_q0: M^-1's diagonal, one O(n) solve a
// dof (MuJoCo averages a Ball's three and a Free joint's translations and rotations)
void dof_invweight0(Model& model, const ArticulationView& art, ArticulationScratch& s) {
  const int n = art.dof_count();
  VecX x(n);
  Scalar* weight = model.joint_invweight0.data() + art.qd_begin();
  for (int k = 0; k < n; ++k) {
    x.setZero();
    x[k] = 1;
    aba_solve(art, s, x.data());
    weight[k] = x[k];
  }
  auto average = [&](int from, int count) {
    const Scalar mean = std::accumulate(weight + from, weight + from + count, Scalar(0)) / count;
    std::fill_n(weight + from, count, mean);
  };
  for (int i = 0; i < art.link_count(); ++i) {
    if (art.type(i) == JointType::Ball) average(art.qd_start(i), 3);
    if (art.type(i) == JointType::Free) average(art.qd_start(i), 3), average(art.qd_start(i) + 3, 3);
  }
}

// the invweight0 J M^-1 J^T of art's tendons, with s as dof_invweight0's: a fixed one's over its dofs, a spatial
// one's share from its pieces on art's links (spans: each spatial tendon's at joint_q0; M is block diagonal over
// articulations, so the shares of a tendon's two articulations add)
void tendon_invweight0(Model& model, const ArticulationView& art, ArticulationScratch& s,
                       const std::vector<std::vector<TendonSpan>>& spans) {
  const int begin = art.qd_begin(), n = art.dof_count();
  VecX J(n), x(n);
  std::vector<int> link_of(model.body_count, -1);
  for (int i = 0; i < art.link_count(); ++i) link_of[art.body(i)] = i;
  for (int i = 0; i < art.link_count(); ++i)
    s.S_world.middleCols(art.qd_start(i), art.dof(i)) =
        motion_xform(s.X_world[i].inverse()) * s.S.middleCols(art.qd_start(i), art.dof(i));
  for (int t = 0; t < model.tendon_count; ++t) {
    J.setZero();
    bool on = false;
    if (is_spatial(model, t)) {
      for (const TendonSpan& span : spans[t])
        for (int k = 0; k < 2; ++k) {
          const int b = span.body[k];
          if (b < 0 || link_of[b] < 0) continue;
          on = true;
          const Vec3 d = (k == 1 ? 1 : -1) * span.scale * span.unit;
          for (int i = link_of[b]; i >= 0; i = art.parent(i))
            for (int m = art.qd_start(i); m < art.qd_start(i) + art.dof(i); ++m) {
              const Vec6 S = s.S_world.col(m);  // [w; v] in the world
              J[m] += d.dot(S.tail<3>() + S.head<3>().cross(span.point[k]));
            }
        }
    } else {
      const int first = model.tendon_start[t], end = model.tendon_start[t + 1];
      on = model.tendon_dof[first] >= begin && model.tendon_dof[first] < begin + n;
      for (int e = first; e < end && on; ++e) J[model.tendon_dof[e] - begin] += model.tendon_coef[e];
    }
    if (!on) continue;
    x = J;
    aba_solve(art, s, x.data());
    model.tendon_invweight0[t] += J.dot(x);
  }
}

}  // namespace

void set_invweight0(Model& model) {
  // inputs: the model at joint_q0; outputs: body_invweight0 (0 for a static body), joint_invweight0 and
  // tendon_invweight0 where a soft row weighs them (else 0)
  model.body_invweight0.assign(2 * static_cast<size_t>(model.body_count), 0);
  model.joint_invweight0.assign(model.joint_dof_count, 0);
  model.tendon_invweight0.assign(model.tendon_count, 0);
  const bool joints = weighs_joints(model);
  // the spatial tendons' pieces at joint_q0, where a soft row weighs them
  std::vector<std::vector<TendonSpan>> spans(model.tendon_count);
  if (joints && model.tendon_path_count > 0) {
    const State q0 = model.state();
    for (int t = 0; t < model.tendon_count; ++t)
      if (is_spatial(model, t)) spatial_tendon(model, t, q0.body_q.data(), spans[t]);
  }
  ArticulationScratch s;
  std::vector<Mat6> Omega;
  std::unordered_map<std::string, int> computed;  // an articulation's defining data -> the first that has it
  std::string key;
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = model.articulation(a);
    if (art.dof_count() == 0) continue;  // (welded to the world: weightless, as MuJoCo's static bodies)
    // a replica of one already computed: the same weights, link by link and dof by dof (its tendons computed anew)
    invweight0_key(model, art, key);
    const auto [first, inserted] = computed.try_emplace(key, a);
    if (!inserted) {
      const ArticulationView same = model.articulation(first->second);
      for (int i = 0; i < art.link_count(); ++i)
        std::copy_n(&model.body_invweight0[2 * same.body(i)], 2, &model.body_invweight0[2 * art.body(i)]);
      std::copy_n(&model.joint_invweight0[same.qd_begin()], art.dof_count(), &model.joint_invweight0[art.qd_begin()]);
      if (!joints || model.tendon_count == 0) continue;
    }
    s.resize(art);
    forward_kinematics(art, model.joint_q0.data() + art.q_begin(), s);
    if (joints && aba_factor(art, nullptr, s) < 0) {
      if (inserted) dof_invweight0(model, art, s);
      tendon_invweight0(model, art, s, spans);
    }
    if (!inserted || osim_inverse(art, s, Omega) >= 0) continue;
    for (int i = 0; i < art.link_count(); ++i) {
      // the COM's velocity v + w x c = v - [c]x w: C = [-[c]x, 1] maps the link's [w; v] to it
      Eigen::Matrix<Scalar, 3, 6> C;
      C << -skew(art.com(i)), Mat3::Identity();
      const int b = art.body(i);
      model.body_invweight0[2 * b] = (C * Omega[i] * C.transpose()).trace() / 3;
      model.body_invweight0[2 * b + 1] = Omega[i].topLeftCorner<3, 3>().trace() / 3;
    }
  }
}

}  // namespace novaphy
