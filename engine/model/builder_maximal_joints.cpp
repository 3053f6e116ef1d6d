// ModelBuilder's maximal-coordinate joints (builder.h): Distance, D6 and Cable, each kept as a six-dof joint whose
// per-dof ranges and gains say what a solver in maximal coordinates holds.
#include <cmath>
#include <limits>
#include <string>

#include "engine/model/builder.h"
#include "engine/model/builder_checks.h"
#include "engine/model/error.h"

namespace novaphy {

namespace {

// a dof that moves freely, and one held at 0 (a locked axis)
JointDofConfig free_dof() { return {}; }
JointDofConfig locked_dof() {
  JointDofConfig dof;
  dof.limit_lower = dof.limit_upper = 0;
  return dof;
}

// a D6's joint frame from its given axes: `frame` its axes (columns, in the parent joint frame), `slot` [k] the
// frame axis given axis k (linear ones first, then angular) lies along. Fails naming a zero or non-finite axis, two
// axes of one kind along one direction, axes neither parallel nor perpendicular, and three that are left-handed
void d6_frame(const std::string& item, const std::vector<JointDofConfig>& linear,
              const std::vector<JointDofConfig>& angular, Mat3& frame, std::vector<int>& slot) {
  std::vector<Vec3> axes;  // the distinct directions, in order
  const size_t given = linear.size() + angular.size();
  for (size_t k = 0; k < given; ++k) {
    const bool is_linear = k < linear.size();
    const size_t i = is_linear ? k : k - linear.size();
    const std::string what = std::string(is_linear ? "linear_axes[" : "angular_axes[") + std::to_string(i) + "]";
    Vec3 axis = (is_linear ? linear[i] : angular[i]).axis;
    check_finite(item, what.c_str(), axis);
    if (axis.norm() < 1e-9) fail(item, ": ", what, " has zero length");
    axis.normalize();
    int found = -1;
    for (size_t a = 0; a < axes.size(); ++a) {
      const Scalar c = axes[a].dot(axis);
      if (std::abs(c) > 1 - 1e-9) {
        if (c < 0) fail(item, ": ", what, " is the reverse of an axis given before; give each direction one way");
        found = static_cast<int>(a);
      } else if (std::abs(c) > 1e-6) {
        fail(item, ": ", what, " is neither parallel nor perpendicular to the axes given before (cosine ", c, ")");
      }
    }
    if (found >= 0) {
      for (size_t j = is_linear ? 0 : linear.size(); j < k; ++j)
        if (slot[j] == found) fail(item, ": ", what, " conflicts with an axis of its kind along the same direction");
    } else {
      found = static_cast<int>(axes.size());
      axes.push_back(axis);
    }
    slot.push_back(found);
  }
  // completed to a right-handed frame
  if (axes.empty()) axes.push_back(Vec3::UnitX());
  if (axes.size() == 1) {
    const Vec3& x = axes[0];
    const Vec3 helper = std::abs(x.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    axes.push_back((helper - helper.dot(x) * x).normalized());
  }
  const Vec3 z = axes[0].cross(axes[1]);
  if (axes.size() == 3 && z.dot(axes[2]) < 0)
    fail(item, ": the three axes are left-handed (the third is minus the first's cross the second); reverse one");
  frame.col(0) = axes[0];
  frame.col(1) = axes[1];
  frame.col(2) = z;
}

}  // namespace

int ModelBuilder::add_joint_distance(int parent, int child, const JointOptions& options, Scalar min_distance,
                                     Scalar max_distance, Scalar compliance) {
  const std::string item = label("joint", joint_count(), options.name) + " (Distance)";
  if (std::isnan(min_distance) || min_distance < 0 || std::isinf(min_distance))
    fail(item, ": min_distance must be finite and >= 0, got ", min_distance);
  if (std::isnan(max_distance) || max_distance < min_distance)
    fail(item, ": max_distance must be >= min_distance (", min_distance, "), got ", max_distance);
  check_nonnegative(item, "compliance", compliance);
  JointRecord joint{JointType::Distance, parent, child, options};
  joint.dofs.assign(6, free_dof());
  joint.dofs[0].limit_lower = min_distance;
  joint.dofs[0].limit_upper = max_distance;
  joint.compliance[0] = compliance;
  return add_joint_record(joint);
}

int ModelBuilder::add_joint_d6(int parent, int child, const JointOptions& options,
                               const std::vector<JointDofConfig>& linear_axes,
                               const std::vector<JointDofConfig>& angular_axes, Scalar linear_compliance,
                               Scalar angular_compliance) {
  const std::string item = label("joint", joint_count(), options.name) + " (D6)";
  if (linear_axes.size() > 3 || angular_axes.size() > 3)
    fail(item, ": at most 3 linear and 3 angular axes, got ", linear_axes.size(), " and ", angular_axes.size());
  check_nonnegative(item, "linear_compliance", linear_compliance);
  check_nonnegative(item, "angular_compliance", angular_compliance);
  Mat3 frame;
  std::vector<int> slot;
  d6_frame(item, linear_axes, angular_axes, frame, slot);
  JointRecord joint{JointType::D6, parent, child, options};
  const Quat turn(frame);
  joint.options.parent_xform.q = (options.parent_xform.q * turn).normalized();
  joint.options.child_xform.q = (options.child_xform.q * turn).normalized();
  joint.dofs.assign(6, locked_dof());
  for (size_t k = 0; k < slot.size(); ++k) {
    const bool is_linear = k < linear_axes.size();
    JointDofConfig dof = is_linear ? linear_axes[k] : angular_axes[k - linear_axes.size()];
    dof.axis = frame.col(slot[k]);
    joint.dofs[(is_linear ? 3 : 0) + slot[k]] = dof;
  }
  joint.compliance[0] = linear_compliance;
  joint.compliance[1] = angular_compliance;
  return add_joint_record(joint);
}

int ModelBuilder::add_joint_cable(int parent, int child, const JointOptions& options, Scalar stretch_compliance,
                                  Scalar bend_compliance) {
  const std::string item = label("joint", joint_count(), options.name) + " (Cable)";
  check_nonnegative(item, "stretch_compliance", stretch_compliance);
  check_nonnegative(item, "bend_compliance", bend_compliance);
  JointRecord joint{JointType::Cable, parent, child, options};
  joint.dofs.assign(6, free_dof());
  joint.compliance[0] = stretch_compliance;
  joint.compliance[1] = bend_compliance;
  return add_joint_record(joint);
}

}  // namespace novaphy
