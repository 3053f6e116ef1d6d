#include "engine/solver/joint_support.h"

#include <sstream>

#include "engine/model/error.h"
#include "kernels/joint.h"

namespace novaphy {

bool JointSupportMatrix::supports(const std::string& joint) const {
  for (const Entry& e : entries)
    if (e.joint == joint) return e.supported;
  fail("unknown joint type '", joint, "'");
}

std::string JointSupportMatrix::to_string() const {
  std::ostringstream os;
  os << solver << " joint support:";
  for (const Entry& e : entries) os << "\n  " << e.joint << ": " << (e.supported ? "yes" : "no");
  return os.str();
}

JointSupportMatrix joint_support(const std::string& solver, bool maximal) {
  return {solver,
          {{"Revolute", true},
           {"Prismatic", true},
           {"Slide", true},
           {"Ball", true},
           {"Fixed", true},
           {"Free", true},
           {"Distance", maximal},
           {"D6", maximal},
           {"Cable", maximal}}};
}

const Model& supported_model(const Model& model, const std::string& solver, bool maximal) {
  if (maximal) return model;
  for (int j = 0; j < model.joint_count; ++j) {
    const auto type = static_cast<JointType>(model.joint_type[j]);
    if (joint_is_six_dof(type) && type != JointType::Free)
      fail(solver, " does not enforce joint ", j, model.joint_name[j].empty() ? "" : " '" + model.joint_name[j] + "'",
           " (", joint_type_name(type), "), a maximal-coordinate joint: use SolverSemiImplicit or SolverXPBD");
  }
  return model;
}

}  // namespace novaphy
