// What joint types a solver enforces (solver.joint_support()), and the refusal of a model with a joint it does not.
#pragma once

#include <string>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

struct JointSupportMatrix {
  struct Entry {
    std::string joint;
    bool supported;
  };
  std::string solver;
  std::vector<Entry> entries;
  bool supports(const std::string& joint) const;  // throws Error for an unknown name
  std::string to_string() const;
};

// every joint type (and the alias Slide) with whether solver `solver` enforces it: the reduced-coordinate ones
// always, the maximal-coordinate ones (Distance, D6, Cable) where `maximal`
JointSupportMatrix joint_support(const std::string& solver, bool maximal);

// `model`, after failing naming its first joint `solver` does not enforce and the solvers that do
const Model& supported_model(const Model& model, const std::string& solver, bool maximal);

}  // namespace novaphy
