#include "engine/solver/parts/applied_wrenches.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "engine/model/actuator.h"
#include "engine/model/body_kinematics.h"
#include "engine/model/tendon.h"

namespace novaphy {

namespace {

constexpr Scalar kMinMass = 1e-15;  // (MuJoCo's mjMINVAL: a body lighter than this feels no fluid)
constexpr Scalar kPi = 3.14159265358979323846;

}  // namespace

ModelWrenches ModelWrenches::of(const Model& model) {
  ModelWrenches w;
  w.gravity_compensation =
      std::any_of(model.body_gravcomp.begin(), model.body_gravcomp.end(), [](Scalar x) { return x != 0; });
  w.fluid = has_fluid(model);
  std::vector<int> link_articulation(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) link_articulation[model.joint_child[j]] = model.joint_articulation[j];
  for (int u = 0; u < model.actuator_count; ++u)
    if (model.actuator_body[u] >= 0) {
      w.site_actuators.push_back(u);
      w.moved_articulations.push_back(link_articulation[model.actuator_body[u]]);
    }
  for (int b = 0; b < model.body_count && w.fluid; ++b)
    if (model.body_mass[b] >= kMinMass && link_articulation[b] >= 0)
      w.fluid_articulations.push_back(link_articulation[b]);
  std::vector<std::vector<int>> on_tendon(model.tendon_count);
  for (int u = 0; u < model.actuator_count; ++u)
    if (model.actuator_joint[u] < 0 && model.actuator_tendon[u] >= 0) on_tendon[model.actuator_tendon[u]].push_back(u);
  w.tendon_actuator_start.push_back(0);
  for (int t = 0; t < model.tendon_count; ++t) {
    if (!is_spatial(model, t)) continue;
    w.spatial_tendons.push_back(t);
    w.tendon_actuators.insert(w.tendon_actuators.end(), on_tendon[t].begin(), on_tendon[t].end());
    w.tendon_actuator_start.push_back(static_cast<int>(w.tendon_actuators.size()));
    for (int e = model.tendon_path_start[t]; e < model.tendon_path_start[t + 1]; ++e)
      if (model.tendon_path_body[e] >= 0) w.moved_articulations.push_back(link_articulation[model.tendon_path_body[e]]);
  }
  w.moved_articulations.insert(w.moved_articulations.end(), w.fluid_articulations.begin(), w.fluid_articulations.end());
  for (std::vector<int>* list : {&w.moved_articulations, &w.fluid_articulations}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  if (!w.moved_articulations.empty()) {
    w.bodies.body_q.assign(7 * static_cast<size_t>(model.body_count), 0);
    w.bodies.body_qd.assign(6 * static_cast<size_t>(model.body_count), 0);
  }
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

namespace {

// MuJoCo's inertia-box model: viscous and quadratic drag on the box of body b's inertia (into wrench, zeroed)
void inertia_box_wrench(const Model& model, int b, const Transform& body_frame, const Vec3& v, const Vec3& w,
                        Scalar wrench[6]) {
  const Scalar mass = model.body_mass[b];
  // the body's principal axes (world frame) and the box of its inertia: side k from the moments about the others
  const Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>> inertia(&model.body_inertia[9 * b]);
  Eigen::SelfAdjointEigenSolver<Mat3> principal;
  principal.computeDirect(Mat3(inertia));
  const Vec3 I = principal.eigenvalues();
  const Mat3 R = body_frame.rotation() * principal.eigenvectors();
  Vec3 box;
  for (int k = 0; k < 3; ++k)
    box[k] = std::sqrt(std::max(Scalar(1e-15), I[(k + 1) % 3] + I[(k + 2) % 3] - I[k]) / mass * 6);
  // the centre of mass's velocity through the wind and the turning, in the principal frame
  const Vec3 lin = R.transpose() * (v - model.wind), ang = R.transpose() * w;
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  const Scalar rho = model.fluid_density, mu = model.fluid_viscosity;
  if (mu > 0) {  // Stokes drag on the sphere of the box's mean side
    const Scalar diameter = box.sum() / 3;
    torque -= (kPi * diameter * diameter * diameter * mu) * ang;
    force -= (3 * kPi * diameter * mu) * lin;
  }
  if (rho > 0) {  // quadratic drag on each face and each turning axis
    for (int k = 0; k < 3; ++k) {
      const Scalar a = box[(k + 1) % 3], c = box[(k + 2) % 3];
      force[k] -= 0.5 * rho * a * c * std::abs(lin[k]) * lin[k];
      torque[k] -= rho * box[k] * (a * a * a * a + c * c * c * c) * std::abs(ang[k]) * ang[k] / 64;
    }
  }
  const Vec3 f = R * force, t = R * torque;
  for (int k = 0; k < 3; ++k) wrench[k] = f[k], wrench[3 + k] = t[k];
}

// MuJoCo's ellipsoid model: fluid ellipsoid e of its body at the world frame `frame`, its centre moving at v (through
// the wind) and turning at w (world frame): the fluid's force and torque about its centre (world frame)
void ellipsoid_wrench(const Model& model, int e, const Transform& frame, const Vec3& v, const Vec3& w, Vec3& force,
                      Vec3& torque) {
  const Scalar rho = model.fluid_density, mu = model.fluid_viscosity;
  const Vec3 r = Eigen::Map<const Vec3>(&model.fluid_ellipsoid_size[3 * e]);
  const Scalar blunt = model.fluid_ellipsoid_drag[3 * e], slender = model.fluid_ellipsoid_drag[3 * e + 1],
               angular_drag = model.fluid_ellipsoid_drag[3 * e + 2];
  const Scalar kutta = model.fluid_ellipsoid_lift[2 * e], magnus = model.fluid_ellipsoid_lift[2 * e + 1];
  const Vec3 added_mass = Eigen::Map<const Vec3>(&model.fluid_ellipsoid_added_mass[3 * e]);
  const Vec3 added_inertia = Eigen::Map<const Vec3>(&model.fluid_ellipsoid_added_inertia[3 * e]);
  // the motion in the ellipsoid's frame
  const Mat3 R = frame.rotation();
  const Vec3 lin = R.transpose() * (v - model.wind), ang = R.transpose() * w;
  const Scalar speed = lin.norm();
  // added mass: the fluid's virtual momenta turned by the motion (their rates, which need the acceleration, left
  // out as MuJoCo leaves them)
  const Vec3 p_lin = rho * added_mass.cwiseProduct(lin), p_ang = rho * added_inertia.cwiseProduct(ang);
  Vec3 f = p_lin.cross(ang), t = p_lin.cross(lin) + p_ang.cross(ang);
  // Magnus lift of the spin through the flow
  const Scalar volume = 4.0 / 3.0 * kPi * r.prod();
  f += magnus * rho * volume * ang.cross(lin);
  // the area the ellipsoid shows the flow, and Kutta lift from the circulation about its projected section
  const Vec3 cross_areas(r[1] * r[2], r[2] * r[0], r[0] * r[1]);  // (each axis' section over pi)
  const Vec3 a2 = cross_areas.cwiseProduct(cross_areas);
  const Scalar shown = a2.cwiseProduct(a2).dot(lin.cwiseProduct(lin));  // sum (r_j r_k)^4 lin_i^2
  const Scalar along = a2.dot(lin.cwiseProduct(lin));                   // sum (r_j r_k lin_i)^2
  const Scalar A_proj = kPi * std::sqrt(shown / std::max(kMinMass, along));
  const Vec3 normal = a2.cwiseProduct(lin);
  const Scalar cos_alpha = along / std::max(kMinMass, speed * shown);
  const Vec3 circulation = kutta * rho * cos_alpha * A_proj * normal.cross(lin);
  f += circulation.cross(lin);
  // drag: Stokes' on the sphere of the semi-axes' mean diameter, and quadratic on the shown and the largest areas
  // (linear) and on each axis' swept moment (angular)
  const Scalar r_max = r.maxCoeff(), r_min = r.minCoeff(), r_mid = r.sum() - r_max - r_min;
  const Scalar diameter = 2.0 / 3.0 * r.sum(), A_max = kPi * r_max * r_mid;
  const Scalar I_max = 8.0 / 15.0 * kPi * r_mid * std::pow(r_max, 4);
  Vec3 swept;
  for (int i = 0; i < 3; ++i) {
    const Scalar I_i = 8.0 / 15.0 * kPi * r[i] * std::pow(std::max(r[(i + 1) % 3], r[(i + 2) % 3]), 4);
    swept[i] = ang[i] * (angular_drag * I_i + slender * (I_max - I_i));
  }
  const Scalar linear = mu * 3 * kPi * diameter + rho * speed * (A_proj * blunt + slender * (A_max - A_proj));
  const Scalar angular = mu * kPi * diameter * diameter * diameter + rho * swept.norm();
  f -= linear * lin;
  t -= angular * ang;
  force = R * f;
  torque = R * t;
}

}  // namespace

void fluid_wrench(const Model& model, int b, const Transform& body_frame, const Vec3& v, const Vec3& w,
                  Scalar wrench[6]) {
  std::fill_n(wrench, 6, Scalar(0));
  if (!(model.body_mass[b] >= kMinMass)) return;
  // the body's fluid ellipsoids (laid out by body), else the box of its inertia
  const auto [first, last] = std::equal_range(model.fluid_ellipsoid_body.begin(), model.fluid_ellipsoid_body.end(), b);
  if (first == last) return inertia_box_wrench(model, b, body_frame, v, w, wrench);
  const Vec3 com = body_frame.apply(Vec3(model.body_com[3 * b], model.body_com[3 * b + 1], model.body_com[3 * b + 2]));
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  for (auto e = first; e != last; ++e) {
    const int k = static_cast<int>(e - model.fluid_ellipsoid_body.begin());
    const Transform frame = body_frame * Transform::from_array(&model.fluid_ellipsoid_frame[7 * k]);
    Vec3 f, t;
    ellipsoid_wrench(model, k, frame, v + w.cross(frame.p - com), w, f, t);
    force += f;
    torque += t + (frame.p - com).cross(f);
  }
  for (int k = 0; k < 3; ++k) wrench[k] = force[k], wrench[3 + k] = torque[k];
}

void applied_wrenches(const Model& model, ModelWrenches& wrenches, const State& state, const Control* control,
                      std::vector<Scalar>& out) {
  out.assign(state.body_f.begin(), state.body_f.end());
  if (wrenches.gravity_compensation)
    for (int b = 0; b < model.body_count; ++b)
      if (model.body_gravcomp[b] != 0) {
        const Vec3 f = gravity_compensation(model, b);
        for (int m = 0; m < 3; ++m) out[6 * static_cast<size_t>(b) + m] += f[m];
      }
  // the bodies where the state's coordinates and velocities put them: their articulations' kinematics
  ArticulationScratch& s = wrenches.scratch;
  State& bodies = wrenches.bodies;
  for (const int a : wrenches.moved_articulations) store_body_state(kinematics(model, state, a, s), s, bodies);
  const Scalar* body_q = bodies.body_q.data();
  auto add = [&](int b, const Scalar wrench[6]) {
    for (int m = 0; m < 6; ++m) out[6 * static_cast<size_t>(b) + m] += wrench[m];
  };
  // the fluid's, on each body at its pose and velocity
  for (const int a : wrenches.fluid_articulations) {
    const ArticulationView art = model.articulation(a);
    for (int i = 0; i < art.link_count(); ++i) {
      const int b = art.body(i);
      const Scalar* qd = &bodies.body_qd[6 * static_cast<size_t>(b)];
      Scalar wrench[6];
      fluid_wrench(model, b, pose_in(body_q, b), Vec3(qd[0], qd[1], qd[2]), Vec3(qd[3], qd[4], qd[5]), wrench);
      add(b, wrench);
    }
  }
  // the spatial tendons' springs and dampers, and the actuators on them
  for (size_t k = 0; k < wrenches.spatial_tendons.size(); ++k) {
    const int t = wrenches.spatial_tendons[k];
    const Scalar length = spatial_tendon(model, t, body_q, wrenches.spans);
    const Scalar velocity = spatial_tendon_velocity(model, wrenches.spans, body_q, bodies.body_qd.data());
    Scalar force = tendon_passive_force(model, t, length, velocity);
    for (int i = wrenches.tendon_actuator_start[k]; i < wrenches.tendon_actuator_start[k + 1] && control; ++i) {
      const int u = wrenches.tendon_actuators[i];
      force += actuator_joint_force(model, u, control->actuator_ctrl[u], length, velocity);
    }
    add_spatial_tendon_force(model, wrenches.spans, body_q, force, out.data());
  }
  if (!control) return;
  for (const int u : wrenches.site_actuators) {
    Scalar wrench[6];
    const int b = model.actuator_body[u];
    site_actuator_wrench(model, u, control->actuator_ctrl[u], pose_in(body_q, b), wrench);
    add(b, wrench);
  }
}

}  // namespace novaphy
