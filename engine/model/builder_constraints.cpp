// ModelBuilder's fixed and spatial tendons, the actuators on them and equality constraints (model.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "engine/model/builder.h"
#include "engine/model/builder_checks.h"

namespace novaphy {

int ModelBuilder::add_tendon(const std::vector<int>& joints, const std::vector<Scalar>& coefs,
                             const TendonOptions& options) {
  const std::string item = label("tendon", tendon_count(), options.name);
  if (joints.empty()) fail(item, ": a tendon needs at least one joint");
  if (joints.size() != coefs.size())
    fail(item, ": ", joints.size(), " joints but ", coefs.size(), " coefficients (one per joint)");
  for (size_t i = 0; i < joints.size(); ++i) {
    check_scalar_joint(item, "a fixed tendon spans Revolute or Prismatic joints", joints[i]);
    check_finite(item, "coefficient", coefs[i]);
  }
  check_tendon_options(item, options);
  tendons_.push_back({joints, coefs, options, {}});
  return tendon_count() - 1;
}

int ModelBuilder::add_spatial_tendon(const std::vector<TendonPathElement>& path, const TendonOptions& options) {
  const std::string item = label("tendon", tendon_count(), options.name) + " (spatial)";
  const int n = static_cast<int>(path.size());
  auto is = [&](int e, TendonPathKind kind) { return e >= 0 && e < n && path[e].kind == kind; };
  auto refuse = [&](int e, const auto&... why) { fail(item, ": path element ", e, " ", why...); };
  if (n < 2 || !is(0, TendonPathKind::Site) || !is(n - 1, TendonPathKind::Site))
    fail(item, ": a path starts and ends at a site (", n, " elements given)");
  for (int e = 0; e < n; ++e) {
    const TendonPathElement& x = path[e];
    if (x.body < -1 || x.body >= body_count())
      refuse(e, "has body ", x.body, ", out of range [-1, ", body_count(), ")");
    checked_transform(item, "path frame", x.frame);
    switch (x.kind) {
      case TendonPathKind::Site: break;
      case TendonPathKind::Sphere:
      case TendonPathKind::Cylinder: {
        if (!(x.size > 0) || !std::isfinite(x.size)) refuse(e, "wraps around a geom whose radius is not > 0");
        const int after = is(e + 1, TendonPathKind::SideSite) ? e + 2 : e + 1;
        if (!is(e - 1, TendonPathKind::Site) || !is(after, TendonPathKind::Site))
          refuse(e, "wraps around a geom that is not between two sites (its side site right after it)");
        break;
      }
      case TendonPathKind::SideSite:
        if (!is(e - 1, TendonPathKind::Sphere) && !is(e - 1, TendonPathKind::Cylinder))
          refuse(e, "is a side site that does not follow a sphere or cylinder");
        break;
      case TendonPathKind::Pulley:
        if (!(x.size > 0) || !std::isfinite(x.size)) refuse(e, "is a pulley whose divisor is not > 0");
        if (!is(e - 1, TendonPathKind::Site) || !is(e + 1, TendonPathKind::Site))
          refuse(e, "is a pulley that is not between two sites");
        break;
      default: refuse(e, "is of no TendonPathKind");
    }
  }
  if (std::none_of(path.begin(), path.end(), [](const TendonPathElement& x) { return x.body >= 0; }))
    fail(item, ": its path rides on the world alone (nothing it could move)");
  check_tendon_options(item, options);
  tendons_.push_back({{}, {}, options, path});
  return tendon_count() - 1;
}

int ModelBuilder::tendon_world(int t) const {
  const TendonRecord& tendon = tendons_[t];
  if (!tendon.joints.empty()) return body_world_[joints_[tendon.joints[0]].child];
  for (const TendonPathElement& x : tendon.path)
    if (x.body >= 0) return body_world_[x.body];
  return 0;  // (not reached: add_spatial_tendon refuses a path on the world alone)
}

void ModelBuilder::check_tendon_options(const std::string& item, const TendonOptions& options) const {
  check_nonnegative(item, "stiffness", options.stiffness);
  check_nonnegative(item, "damping", options.damping);
  if (std::isinf(options.rest_length)) fail(item, ": rest_length is not finite: ", options.rest_length);
  check_range(item, "limit range", options.limit_lower, options.limit_upper);
  check_solref(item, "limit_solref", options.limit_solref);
  check_solimp(item, "limit_solimp", options.limit_solimp);
  check_nonnegative(item, "frictionloss", options.frictionloss);
  check_solref(item, "friction_solref", options.friction_solref);
  check_solimp(item, "friction_solimp", options.friction_solimp);
}

int ModelBuilder::add_tendon_actuator(int tendon, const ActuatorOptions& options) {
  const std::string item = label("actuator", actuator_count(), options.name);
  if (tendon < 0 || tendon >= tendon_count())
    fail(item, ": tendon index ", tendon, " out of range [0, ", tendon_count(), ")");
  check_actuator(item, options);
  actuators_.push_back({-1, options, tendon});
  return actuator_count() - 1;
}

int ModelBuilder::add_site_actuator(int body, const Transform& site, const std::array<Scalar, 6>& gear,
                                    const ActuatorOptions& options) {
  const std::string item = label("actuator", actuator_count(), options.name);
  if (body < 0 || body >= body_count())
    fail(item, ": a site actuator's body ", body, " out of range [0, ", body_count(), ")");
  const Transform frame = checked_transform(item, "site", site);
  for (Scalar g : gear) check_finite(item, "gear", g);
  check_actuator(item, options);
  if (options.gear != 1)
    fail(item, ": a site actuator's gear is its six numbers (force, torque); options.gear must be 1, got ",
         options.gear);
  if (options.bias[2] != 0)
    fail(item, ": a site actuator's force cannot depend on the site's velocity (bias[2] = ", options.bias[2],
         "): not modelled");
  ActuatorRecord record{-1, options};
  record.body = body;
  const Vec3 force = frame.q * Vec3(gear[0], gear[1], gear[2]);
  const Vec3 torque = frame.q * Vec3(gear[3], gear[4], gear[5]) + frame.p.cross(force);
  for (int k = 0; k < 3; ++k) record.wrench[k] = force[k], record.wrench[3 + k] = torque[k];
  actuators_.push_back(record);
  return actuator_count() - 1;
}

void ModelBuilder::join_tendon_articulations(std::vector<JointRecord>& joints, int& articulation_count) const {
  // union-find over articulations, each group named by its smallest articulation
  std::vector<int> root(articulation_count);
  std::iota(root.begin(), root.end(), 0);
  const auto find = [&root](int a) {
    while (root[a] != a) a = root[a] = root[root[a]];
    return a;
  };
  std::vector<char> floating(articulation_count, 0);
  for (const JointRecord& joint : joints) floating[joint.articulation] |= joint.type == JointType::Free;
  std::vector<int> joined_by(articulation_count, -1);  // by a group's root: the last tendon that joined it
  bool joined = false;
  for (int t = 0; t < tendon_count(); ++t) {
    const TendonRecord& tendon = tendons_[t];
    if (tendon.joints.empty()) continue;  // (a spatial tendon's rows join its articulations)
    const int j0 = tendon.joints[0];
    for (const int j : tendon.joints) {
      const int a = find(joints[j0].articulation), b = find(joints[j].articulation);
      if (a == b) continue;
      const auto refuse = [&](const char* why) {
        fail(label("tendon", t, tendon.options.name), ": its joints ", j0, " and ", j,
             " are in different articulations, ", why);
      };
      if (std::min(a, b) < articulation_count_) refuse("one given by add_articulation");
      if (floating[a] || floating[b]) refuse("one of them floating (a tendon joins articulations of fixed base only)");
      root[std::max(a, b)] = std::min(a, b);
      joined_by[std::min(a, b)] = t;
      joined = true;
    }
  }
  if (!joined) return;
  // number the groups in order; a joined group must be one run of joints
  std::vector<int> id(articulation_count, -1);
  int count = 0;
  for (int a = 0; a < articulation_count; ++a)
    if (find(a) == a) id[a] = count++;
  std::vector<char> ended(count, 0);
  int previous = -1;
  for (JointRecord& joint : joints) {
    const int group = find(joint.articulation);
    joint.articulation = id[group];
    if (joint.articulation == previous) continue;
    if (previous >= 0) ended[previous] = 1;
    if (ended[joint.articulation] && joined_by[group] >= 0) {
      const int t = joined_by[group];
      fail(label("tendon", t, tendons_[t].options.name),
           ": joins articulations whose joints are not one after another (add each one's joints after the other's)");
    }
    previous = joint.articulation;
  }
  articulation_count = count;
}

void ModelBuilder::lay_out_tendons(Model& model) const {
  model.tendon_start.assign(1, 0);
  model.tendon_path_start.assign(1, 0);
  std::vector<int> body_articulation(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) body_articulation[model.joint_child[j]] = model.joint_articulation[j];
  for (const TendonRecord& tendon : tendons_) {
    const int t = static_cast<int>(model.tendon_name.size());
    // a spatial tendon's path; its bodies in at most two articulations (a row of the step spans two)
    std::vector<int> articulations;
    for (const TendonPathElement& x : tendon.path) {
      model.tendon_path_kind.push_back(static_cast<int>(x.kind));
      model.tendon_path_body.push_back(x.body);
      model.tendon_path_frame.resize(model.tendon_path_frame.size() + 7);
      x.frame.to_array(&model.tendon_path_frame[model.tendon_path_frame.size() - 7]);
      model.tendon_path_size.push_back(x.size);
      const int a = x.body < 0 ? -1 : body_articulation[x.body];
      if (a >= 0 && std::find(articulations.begin(), articulations.end(), a) == articulations.end())
        articulations.push_back(a);
    }
    if (articulations.size() > 2)
      fail(label("tendon", t, tendon.options.name), " (spatial): its path rides on bodies of ", articulations.size(),
           " articulations (", articulations[0], ", ", articulations[1], ", ", articulations[2],
           "...); a spatial tendon joins at most two");
    model.tendon_path_start.push_back(static_cast<int>(model.tendon_path_kind.size()));
    Scalar length = 0;
    for (size_t i = 0; i < tendon.joints.size(); ++i) {
      const int j = tendon.joints[i];
      model.tendon_coord.push_back(model.joint_q_start[j]);
      model.tendon_dof.push_back(model.joint_qd_start[j]);
      model.tendon_coef.push_back(tendon.coefs[i]);
      length += tendon.coefs[i] * model.joint_q0[model.joint_q_start[j]];
    }
    model.tendon_start.push_back(static_cast<int>(model.tendon_coef.size()));
    const TendonOptions& o = tendon.options;
    model.tendon_stiffness.push_back(o.stiffness);
    model.tendon_damping.push_back(o.damping);
    // (a spatial tendon's length at joint_q0: set_spatial_rest_lengths, once the bodies are laid out)
    model.tendon_rest_length.push_back(std::isnan(o.rest_length) && tendon.path.empty() ? length : o.rest_length);
    model.tendon_limit_lower.push_back(o.limit_lower);
    model.tendon_limit_upper.push_back(o.limit_upper);
    model.tendon_limit_solref.insert(model.tendon_limit_solref.end(), o.limit_solref.begin(), o.limit_solref.end());
    model.tendon_limit_solimp.insert(model.tendon_limit_solimp.end(), o.limit_solimp.begin(), o.limit_solimp.end());
    model.tendon_frictionloss.push_back(o.frictionloss);
    model.tendon_friction_solref.insert(model.tendon_friction_solref.end(), o.friction_solref.begin(),
                                        o.friction_solref.end());
    model.tendon_friction_solimp.insert(model.tendon_friction_solimp.end(), o.friction_solimp.begin(),
                                        o.friction_solimp.end());
    model.tendon_invweight0.push_back(0);  // (set_invweight0)
    model.tendon_name.push_back(o.name);
  }
  model.tendon_count = tendon_count();
  model.tendon_entry_count = static_cast<int>(model.tendon_coef.size());
  model.tendon_path_count = static_cast<int>(model.tendon_path_kind.size());
}

int ModelBuilder::add_connect(int body1, int body2, const Vec3& anchor, const std::string& name, const Vec3& anchor2) {
  const std::string item = label("equality", equality_count(), name) + " (connect)";
  if (body1 < 0 || body1 >= body_count()) fail(item, ": body1 index ", body1, " out of range [0, ", body_count(), ")");
  if (body2 < -1 || body2 >= body_count())
    fail(item, ": body2 index ", body2, " out of range [-1, ", body_count(), ")");
  if (body1 == body2) fail(item, ": connects body ", body1, " to itself");
  check_finite(item, "anchor", anchor);
  if (!anchor2.array().isNaN().all()) check_finite(item, "anchor2", anchor2);
  EqualityRecord e{EqualityType::Connect, {body1, body2}, {}, name};
  for (int k = 0; k < 3; ++k) e.data[k] = anchor[k], e.data[3 + k] = anchor2[k];
  equalities_.push_back(e);
  return equality_count() - 1;
}

int ModelBuilder::add_weld(int body1, int body2, const std::string& name, const Vec3& anchor,
                           const std::optional<Transform>& relative) {
  const std::string item = label("equality", equality_count(), name) + " (weld)";
  for (const int b : {body1, body2})
    if (b < -1 || b >= body_count()) fail(item, ": body index ", b, " out of range [-1, ", body_count(), ")");
  if (body1 == body2) fail(item, ": welds body ", body1, " to itself");
  check_finite(item, "anchor", anchor);
  // data: the anchor in body1's frame (set by lay_out_equalities without `relative`), in body2's, the orientation
  EqualityRecord e{EqualityType::Weld, {body1, body2}, {}, name};
  std::fill(e.data, e.data + 10, std::numeric_limits<Scalar>::quiet_NaN());
  for (int k = 0; k < 3; ++k) e.data[3 + k] = anchor[k];
  if (relative) {
    const Transform T = checked_transform(item, "relative", *relative);
    const Vec3 p = T.apply(anchor);
    for (int k = 0; k < 3; ++k) e.data[k] = p[k];
    Eigen::Map<Eigen::Vector4d>(e.data + 6) = T.q.coeffs();
  }
  equalities_.push_back(e);
  return equality_count() - 1;
}

int ModelBuilder::add_joint_coupling(int joint1, int joint2, const std::array<Scalar, 5>& poly,
                                     const std::string& name) {
  const std::string item = label("equality", equality_count(), name) + " (joint coupling)";
  for (const int j : {joint1, joint2})
    if (j != joint2 || j != -1) check_scalar_joint(item, "couples Revolute or Prismatic joints", j);
  if (joint1 == joint2) fail(item, ": couples joint ", joint1, " to itself");
  EqualityRecord e{EqualityType::JointCoupling, {joint1, joint2}, {}, name};
  for (int k = 0; k < 5; ++k) {
    check_finite(item, "poly", poly[k]);
    e.data[k] = poly[k];
  }
  equalities_.push_back(e);
  return equality_count() - 1;
}

void ModelBuilder::set_equality_softness(int e, const std::array<Scalar, 2>& solref,
                                         const std::array<Scalar, 5>& solimp) {
  if (e < 0 || e >= equality_count())
    fail("set_equality_softness: equality ", e, " out of range [0, ", equality_count(), ")");
  const std::string item = label("equality", e, equalities_[e].name);
  check_solref(item, "solref", solref);
  check_solimp(item, "solimp", solimp);
  equalities_[e].solref = solref;
  equalities_[e].solimp = solimp;
}

void ModelBuilder::lay_out_equalities(Model& model) const {
  const State initial = equalities_.empty() ? State{} : model.state();
  for (const EqualityRecord& record : equalities_) {
    EqualityRecord e = record;
    if (e.type == EqualityType::Connect && std::isnan(e.data[3])) {
      // body2's point that coincides with the anchor at the initial coordinates, in body2's frame
      const Vec3 p = body_pose(initial, e.object[1])
                         .inverse()
                         .apply(body_pose(initial, e.object[0]).apply(Vec3(e.data[0], e.data[1], e.data[2])));
      for (int k = 0; k < 3; ++k) e.data[3 + k] = p[k];
    }
    if (e.type == EqualityType::JointCoupling)
      for (int k = 0; k < 2; ++k)
        e.data[5 + k] = e.object[k] < 0 ? 0 : model.joint_q0[model.joint_q_start[e.object[k]]];
    model.equality_type.push_back(static_cast<int>(e.type));
    model.equality_object.insert(model.equality_object.end(), {e.object[0], e.object[1]});
    if (e.type == EqualityType::Weld && std::isnan(e.data[6])) {
      // body2's pose in body1's at the initial coordinates
      const Transform relative = body_pose(initial, e.object[0]).inverse() * body_pose(initial, e.object[1]);
      const Vec3 p = relative.apply(Vec3(e.data[3], e.data[4], e.data[5]));
      for (int k = 0; k < 3; ++k) e.data[k] = p[k];
      Eigen::Map<Eigen::Vector4d>(e.data + 6) = relative.q.coeffs();
    }
    model.equality_data.insert(model.equality_data.end(), e.data, e.data + 10);
    model.equality_solref.insert(model.equality_solref.end(), e.solref.begin(), e.solref.end());
    model.equality_solimp.insert(model.equality_solimp.end(), e.solimp.begin(), e.solimp.end());
    model.equality_name.push_back(e.name);
  }
  model.equality_count = equality_count();
}

}  // namespace novaphy
