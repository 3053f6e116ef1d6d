#include "engine/sensors/sensors.h"

#include <algorithm>
#include <cmath>

#include "engine/model/group_by_key.h"
#include "engine/model/spatial_tendon.h"
#include "engine/sensors/zone.h"
#include "engine/threads/parallel.h"
#include "kernels/fk.h"
#include "kernels/rnea.h"

namespace novaphy {

namespace {

bool dynamics_sensor(SensorType type) {
  return type == SensorType::FrameLinAcc || type == SensorType::FrameAngAcc || type == SensorType::Accelerometer ||
         type == SensorType::Force || type == SensorType::Torque;
}

bool contact_sensor(SensorType type) { return type == SensorType::Touch || type == SensorType::ContactForce; }

// the start state alone decides the sensor's values (read_start)
bool start_sensor(SensorType type) { return !dynamics_sensor(type) && !contact_sensor(type); }

// values that are directions or orientations keep their length under a cutoff (MuJoCo's axis and quaternion data)
bool cut(SensorType type) {
  return type != SensorType::FrameQuat && type != SensorType::BallQuat && type != SensorType::FrameXAxis &&
         type != SensorType::FrameYAxis && type != SensorType::FrameZAxis;
}

// the world a contact is in: its moving bodies'
int contact_world(const Model& model, const Contacts& contacts, int c) {
  const int b = contacts.contact_body_a[c] >= 0 ? contacts.contact_body_a[c] : contacts.contact_body_b[c];
  return b >= 0 ? model.body_world[b] : -1;
}

Vec3 vec3_at(const std::vector<Scalar>& v, int c) { return Eigen::Map<const Vec3>(&v[3 * static_cast<size_t>(c)]); }

}  // namespace

Sensors::Sensors(const Model& model) : model_(model) {
  body_art_.assign(model.body_count, -1);
  body_link_.assign(model.body_count, -1);
  for (int a = 0; a < model.articulation_count; ++a)
    for (int j = model.articulation_start[a]; j < model.articulation_start[a + 1]; ++j) {
      body_art_[model.joint_child[j]] = a;
      body_link_[model.joint_child[j]] = j - model.articulation_start[a];
    }
  worlds_.resize(model.world_count);
  for (int s = 0; s < model.sensor_count; ++s) {
    WorldSensors& w = worlds_[model.sensor_world[s]];
    if (w.sensor_end == w.sensor_begin) w.sensor_begin = s;
    w.sensor_end = s + 1;
    const SensorType type = static_cast<SensorType>(model.sensor_type[s]);
    w.dynamics |= dynamics_sensor(type);
    dynamics_ |= dynamics_sensor(type);
    contacts_ |= contact_sensor(type) || dynamics_sensor(type);
    const int body = model.sensor_object[s];
    if (!dynamics_sensor(type) || body < 0) continue;
    if (std::find(w.articulations.begin(), w.articulations.end(), body_art_[body]) == w.articulations.end())
      w.articulations.push_back(body_art_[body]);
  }
  start_values_.assign(model.sensor_value_count, 0);
  frame_.assign(model.sensor_count, Transform::identity());
}

void Sensors::read_start(const State& start, int threads) {
  if (empty()) return;
  parallel_for(std::clamp(threads, 1, model_.world_count), model_.world_count, [&](int w) {
    if (worlds_[w].sensor_end > worlds_[w].sensor_begin) read_world_start(w, start);
  });
}

void Sensors::read_world_start(int w, const State& start) {
  const WorldSensors& world = worlds_[w];
  const Model& m = model_;
  const Scalar *q = start.joint_q.data(), *qd = start.joint_qd.data();
  const Vec3 gravity = Eigen::Map<const Vec3>(&m.world_gravity[3 * static_cast<size_t>(w)]);
  const auto body_pose = [&](int b) { return Transform::from_array(&start.body_q[7 * static_cast<size_t>(b)]); };
  for (int sensor = world.sensor_begin; sensor < world.sensor_end; ++sensor) {
    const SensorType type = static_cast<SensorType>(m.sensor_type[sensor]);
    if (dynamics_sensor(type)) continue;
    const int object = m.sensor_object[sensor];
    Scalar* out = start_values_.data() + m.sensor_start[sensor];
    Eigen::Map<Vec3> out3(out);
    const auto tendon_sum = [&](const Scalar* x, const int* index) {
      Scalar sum = 0;
      for (int e = m.tendon_start[object]; e < m.tendon_start[object + 1]; ++e) sum += m.tendon_coef[e] * x[index[e]];
      return sum;
    };
    switch (sensor_object_kind(type)) {
      case SensorObject::Joint: {
        const int c = m.joint_q_start[object], d = m.joint_qd_start[object];
        if (type == SensorType::JointPos) out[0] = q[c];
        if (type == SensorType::JointVel) out[0] = qd[d];
        if (type == SensorType::BallQuat) {
          const Quat r = Quat(q[c + 3], q[c], q[c + 1], q[c + 2]).normalized();
          out[0] = r.w(), out[1] = r.x(), out[2] = r.y(), out[3] = r.z();
        }
        if (type == SensorType::BallAngVel) out3 = Eigen::Map<const Vec3>(qd + d);
        break;
      }
      case SensorObject::Tendon:
        if (is_spatial(m, object)) {
          thread_local std::vector<TendonSpan> spans;  // (the thread's, kept from step to step)
          const Scalar length = spatial_tendon(m, object, start.body_q.data(), spans);
          out[0] = type == SensorType::TendonPos
                       ? length
                       : spatial_tendon_velocity(m, spans, start.body_q.data(), start.body_qd.data());
        } else {
          out[0] = type == SensorType::TendonPos ? tendon_sum(q, m.tendon_coord.data())
                                                 : tendon_sum(qd, m.tendon_dof.data());
        }
        break;
      case SensorObject::Body: {
        // the frame F on the body (the world for a sensor of the world): its pose X in the world, and the world
        // velocity of its origin (the body's centre of mass' plus omega x the arm from it) and angular velocity
        const Transform F = Transform::from_array(&m.sensor_frame[7 * static_cast<size_t>(sensor)]);
        const Transform body = object >= 0 ? body_pose(object) : Transform::identity();
        const Transform X = body * F;
        Vec3 omega = Vec3::Zero(), velocity = Vec3::Zero();
        if (object >= 0) {
          const Scalar* body_qd = &start.body_qd[6 * static_cast<size_t>(object)];
          const Vec3 com = Eigen::Map<const Vec3>(&m.body_com[3 * static_cast<size_t>(object)]);
          omega = Eigen::Map<const Vec3>(body_qd + 3);
          velocity = Eigen::Map<const Vec3>(body_qd) + omega.cross(body.q * (F.p - com));
        }
        switch (type) {
          case SensorType::FramePos: out3 = X.p; break;
          case SensorType::FrameQuat: {
            const Quat o = X.q.normalized();
            out[0] = o.w(), out[1] = o.x(), out[2] = o.y(), out[3] = o.z();
            break;
          }
          case SensorType::FrameXAxis: out3 = X.q * Vec3::UnitX(); break;
          case SensorType::FrameYAxis: out3 = X.q * Vec3::UnitY(); break;
          case SensorType::FrameZAxis: out3 = X.q * Vec3::UnitZ(); break;
          case SensorType::FrameLinVel: out3 = velocity; break;
          case SensorType::FrameAngVel: out3 = omega; break;
          case SensorType::Gyro: out3 = X.q.conjugate() * omega; break;
          case SensorType::Velocimeter: out3 = X.q.conjugate() * velocity; break;
          case SensorType::ProjectedGravity: {
            const Scalar g = gravity.norm();
            out3 = g > 0 ? Vec3(X.q.conjugate() * gravity / g) : Vec3::Zero();
            break;
          }
          case SensorType::SubtreeCom: {
            // the bodies whose chain to the root passes through the sensor's
            const ArticulationView art = m.articulation(body_art_[object]);
            const int i = body_link_[object];
            Scalar mass = 0;
            Vec3 moment = Vec3::Zero();
            for (int j = i; j < art.link_count(); ++j) {
              int up = j;
              while (up > i) up = art.parent(up);
              if (up != i) continue;
              const Scalar mj = m.body_mass[art.body(j)];
              mass += mj;
              moment += mj * body_pose(art.body(j)).apply(art.com(j));
            }
            out3 = mass > 0 ? Vec3(moment / mass) : X.p;
            break;
          }
          case SensorType::Touch:
          case SensorType::ContactForce: frame_[sensor] = X; break;
          default: break;
        }
        break;
      }
    }
  }
}

void Sensors::evaluate(const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                       const Contacts& contacts, Scalar dt, Scalar* sensor_data, int threads) {
  if (empty()) return;
  // the contacts by world (a counting sort, in the contacts' order within a world)
  const int contact_count = contacts_ ? contacts.contact_count : 0;
  contact_start_.resize(model_.world_count + 1);
  contact_order_.resize(contact_count);
  contact_next_.resize(model_.world_count + 1);
  group_by_key(
      contact_count, model_.world_count, [&](int c) { return contact_world(model_, contacts, c); },
      contact_start_.data(), contact_order_.data(), contact_next_.data());
  const int team = std::clamp(threads, 1, model_.world_count);
  scratch_.resize(team);
  parallel_for(team, model_.world_count, [&](int w) {
    if (worlds_[w].sensor_end > worlds_[w].sensor_begin)
      evaluate_world(w, q, qd, qd_next, body_f, contacts, dt, sensor_data, scratch_[omp_get_thread_num()]);
  });
}

void Sensors::evaluate_world(int w, const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                             const Contacts& contacts, Scalar dt, Scalar* sensor_data, Scratch& scratch) const {
  const WorldSensors& world = worlds_[w];
  const Model& m = model_;
  const int* world_contacts = contact_order_.data() + contact_start_[w];
  const int contact_count = contact_start_[w + 1] - contact_start_[w];
  // the kinematics at the step's start of each articulation whose accelerations or forces a sensor reads, and its
  // inverse dynamics at the step's accelerations with the applied wrenches and the contacts' forces (s.a, s.f)
  if (scratch.arts.size() < world.articulations.size()) scratch.arts.resize(world.articulations.size());
  if (world.dynamics) scratch.wrench.resize(6 * static_cast<size_t>(m.body_count));
  for (size_t k = 0; k < world.articulations.size(); ++k) {
    const ArticulationView art = m.articulation(world.articulations[k]);
    ArticulationScratch& s = scratch.arts[k];
    s.resize(art);
    forward_kinematics(art, q + art.q_begin(), s);
    forward_velocity(art, qd + art.qd_begin(), s);
    for (int i = 0; i < art.link_count(); ++i) {
      const size_t b = art.body(i);
      std::copy_n(body_f + 6 * b, 6, scratch.wrench.begin() + 6 * b);
    }
  }
  const auto link_of = [&](int body, const ArticulationScratch*& s) {
    const auto it = std::find(world.articulations.begin(), world.articulations.end(), body_art_[body]);
    s = it == world.articulations.end() ? nullptr : &scratch.arts[it - world.articulations.begin()];
    return body_link_[body];
  };
  if (world.dynamics) {
    for (int k = 0; k < contact_count; ++k) {
      const int c = world_contacts[k];
      const Vec3 impulse = vec3_at(contacts.contact_impulse, c), spin = vec3_at(contacts.contact_spin_impulse, c);
      const Vec3 point = vec3_at(contacts.contact_point, c);
      for (const int side : {0, 1}) {
        const int body = side == 0 ? contacts.contact_body_a[c] : contacts.contact_body_b[c];
        const ArticulationScratch* s = nullptr;
        if (body < 0) continue;
        const int i = link_of(body, s);
        if (s == nullptr) continue;
        const Scalar sign = side == 0 ? -1 : 1;
        const Vec3 force = sign / dt * impulse;
        const Vec3 com = s->X_world[i].apply(Eigen::Map<const Vec3>(&m.body_com[3 * static_cast<size_t>(body)]));
        Scalar* wrench = &scratch.wrench[6 * static_cast<size_t>(body)];
        Eigen::Map<Vec3>(wrench) += force;
        Eigen::Map<Vec3>(wrench + 3) += (point - com).cross(force) + sign / dt * spin;
      }
    }
    for (size_t k = 0; k < world.articulations.size(); ++k) {
      const ArticulationView art = m.articulation(world.articulations[k]);
      const int n = art.dof_count();
      scratch.qdd.resize(n);
      scratch.tau.resize(n);
      for (int d = 0; d < n; ++d) scratch.qdd[d] = (qd_next[art.qd_begin() + d] - qd[art.qd_begin() + d]) / dt;
      rnea(art, scratch.qdd.data(), art.gravity(), scratch.wrench.data(), scratch.arts[k], scratch.tau.data());
    }
  }
  const Vec3 gravity = Eigen::Map<const Vec3>(&m.world_gravity[3 * static_cast<size_t>(w)]);
  for (int sensor = world.sensor_begin; sensor < world.sensor_end; ++sensor) {
    const SensorType type = static_cast<SensorType>(m.sensor_type[sensor]);
    const int object = m.sensor_object[sensor];
    Scalar* out = sensor_data + m.sensor_start[sensor];
    const int dim = m.sensor_start[sensor + 1] - m.sensor_start[sensor];
    Eigen::Map<Vec3> out3(out);
    if (start_sensor(type)) {
      std::copy_n(start_values_.data() + m.sensor_start[sensor], dim, out);
    } else if (contact_sensor(type)) {
      const Transform& X = frame_[sensor];
      const Transform to_frame = X.inverse();
      Vec3 total = Vec3::Zero();
      Scalar touch = 0;
      const ShapeType zone = static_cast<ShapeType>(static_cast<int>(m.sensor_zone[4 * static_cast<size_t>(sensor)]));
      const Vec3 zone_size = Eigen::Map<const Vec3>(&m.sensor_zone[4 * static_cast<size_t>(sensor) + 1]);
      const int shape = m.sensor_shape[sensor];
      for (int k = 0; k < contact_count; ++k) {
        const int c = world_contacts[k];
        // the contact's sides on the sensor's body, or on its one shape
        const bool on_a = shape < 0 ? contacts.contact_body_a[c] == object : contacts.contact_shape_a[c] == shape;
        const bool on_b = shape < 0 ? contacts.contact_body_b[c] == object : contacts.contact_shape_b[c] == shape;
        if (on_a == on_b) continue;
        const Vec3 impulse = vec3_at(contacts.contact_impulse, c), normal = vec3_at(contacts.contact_normal, c);
        total += (on_b ? 1 : -1) / dt * impulse;
        const Scalar normal_force = impulse.dot(normal) / dt;
        if (normal_force <= 0) continue;
        // MuJoCo's ray: from the contact point, away from the sensor's body
        const Vec3 ray = on_a ? normal : Vec3(-normal);
        if (static_cast<int>(zone) < 0 ||
            ray_meets_zone(zone, zone_size, to_frame.apply(vec3_at(contacts.contact_point, c)), to_frame.q * ray))
          touch += normal_force;
      }
      if (type == SensorType::Touch)
        out[0] = touch;
      else
        out3 = total;
    } else {
      // accelerations and forces: the frame F on link i (the world for a sensor of the world), the link's motion
      // and force at F's origin r, in link coordinates
      const Transform F = Transform::from_array(&m.sensor_frame[7 * static_cast<size_t>(sensor)]);
      const ArticulationScratch* s = nullptr;
      const int i = object >= 0 ? link_of(object, s) : -1;
      const Mat3 R_link = s ? s->X_world[i].rotation() : Mat3::Identity(), R_frame = F.rotation();
      const Vec3 r = F.p;
      Vec6 v = Vec6::Zero(), a = Vec6::Zero(), f = Vec6::Zero();
      a.tail<3>() = -gravity;
      if (s) v = s->v[i], a = s->a[i], f = s->f[i];
      const Vec3 omega = v.head<3>(), velocity = v.tail<3>() + omega.cross(r);
      const Vec3 alpha = a.head<3>(), acceleration = a.tail<3>() + alpha.cross(r) + omega.cross(velocity);
      switch (type) {
        case SensorType::FrameLinAcc: out3 = R_link * acceleration; break;
        case SensorType::FrameAngAcc: out3 = R_link * alpha; break;
        case SensorType::Accelerometer: out3 = R_frame.transpose() * acceleration; break;
        case SensorType::Force: out3 = R_frame.transpose() * f.tail<3>(); break;
        case SensorType::Torque: out3 = R_frame.transpose() * (f.head<3>() - r.cross(f.tail<3>())); break;
        default: break;
      }
    }
    const Scalar cutoff = m.sensor_cutoff[sensor];
    if (cutoff > 0 && cut(type))
      for (int k = 0; k < dim; ++k)
        out[k] = type == SensorType::Touch ? std::min(out[k], cutoff) : std::clamp(out[k], -cutoff, cutoff);
  }
}

}  // namespace novaphy
