#include "engine/solver/parts/applied_wrenches.h"

#include <algorithm>

#include "engine/model/actuator.h"
#include "engine/model/body_kinematics.h"

namespace novaphy {

ModelWrenches ModelWrenches::of(const Model& model) {
  ModelWrenches w;
  w.gravity_compensation =
      std::any_of(model.body_gravcomp.begin(), model.body_gravcomp.end(), [](Scalar x) { return x != 0; });
  std::vector<int> link_articulation(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) link_articulation[model.joint_child[j]] = model.joint_articulation[j];
  for (int u = 0; u < model.actuator_count; ++u)
    if (model.actuator_body[u] >= 0) {
      w.site_actuators.push_back(u);
      w.site_articulations.push_back(link_articulation[model.actuator_body[u]]);
    }
  std::sort(w.site_articulations.begin(), w.site_articulations.end());
  w.site_articulations.erase(std::unique(w.site_articulations.begin(), w.site_articulations.end()),
                             w.site_articulations.end());
  return w;
}

Vec3 gravity_compensation(const Model& model, int b) {
  const int w = std::max(0, model.body_world[b]);
  const Vec3 g(model.world_gravity[3 * w], model.world_gravity[3 * w + 1], model.world_gravity[3 * w + 2]);
  return -(model.body_gravcomp[b] * model.body_mass[b]) * g;
}

void site_actuator_wrench(const Model& model, int u, Scalar ctrl, const Transform& body_frame, Scalar wrench[6]) {
  // the actuator's force with no position or velocity (a site's length is 0; its velocity term is refused)
  const Scalar f = actuator_joint_force(model, u, ctrl, 0, 0);
  const Scalar* unit = &model.actuator_wrench[6 * static_cast<size_t>(u)];
  const int b = model.actuator_body[u];
  const Vec3 force = body_frame.q * Vec3(f * unit[0], f * unit[1], f * unit[2]);
  const Vec3 about_origin = body_frame.q * Vec3(f * unit[3], f * unit[4], f * unit[5]);
  const Vec3 com = body_frame.q * Vec3(model.body_com[3 * b], model.body_com[3 * b + 1], model.body_com[3 * b + 2]);
  const Vec3 torque = about_origin - com.cross(force);
  for (int k = 0; k < 3; ++k) wrench[k] = force[k], wrench[3 + k] = torque[k];
}

void applied_wrenches(const Model& model, const ModelWrenches& wrenches, const State& state, const Control* control,
                      std::vector<Scalar>& out) {
  out.assign(state.body_f.begin(), state.body_f.end());
  if (wrenches.gravity_compensation)
    for (int b = 0; b < model.body_count; ++b)
      if (model.body_gravcomp[b] != 0) {
        const Vec3 f = gravity_compensation(model, b);
        for (int m = 0; m < 3; ++m) out[6 * static_cast<size_t>(b) + m] += f[m];
      }
  if (!control || wrenches.site_actuators.empty()) return;
  // the site actuators' bodies where joint_q puts them: their articulations' forward kinematics
  ArticulationScratch s;
  std::vector<Transform> frame(model.body_count);
  for (int a : wrenches.site_articulations) {
    const ArticulationView art = kinematics(model, state, a, s);
    for (int i = 0; i < art.link_count(); ++i) frame[art.body(i)] = s.X_world[i];
  }
  for (int u : wrenches.site_actuators) {
    Scalar wrench[6];
    const int b = model.actuator_body[u];
    site_actuator_wrench(model, u, control->actuator_ctrl[u], frame[b], wrench);
    for (int m = 0; m < 6; ++m) out[6 * static_cast<size_t>(b) + m] += wrench[m];
  }
}

}  // namespace novaphy
