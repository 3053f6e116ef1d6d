// MuJoCo as the oracle: one MJCF loaded into both engines, compared at random states (contacts
// and limits off) on body poses and velocities, the mass matrix, the bias forces and the
// forward-dynamics accelerations under joint forces, body wrenches and motor commands, each
// converted to NovaPhy's coordinates first.
#pragma once

#include <random>
#include <string>

#include "engine/import/mjcf_import.h"

namespace novaphy {

struct OracleErrors {
  // max |novaphy - mujoco| / max(1, max |mujoco|) over the quantity
  Scalar body_pose = 0, body_velocity = 0, mass_matrix = 0, bias = 0, qdd_crba = 0, qdd_aba = 0, qdd_batched = 0;
  Scalar max() const;
  void accumulate(const OracleErrors& other);  // elementwise maximum
};

class MujocoOracle {
 public:
  explicit MujocoOracle(const std::string& path);
  ~MujocoOracle();
  MujocoOracle(const MujocoOracle&) = delete;
  MujocoOracle& operator=(const MujocoOracle&) = delete;

  // draws a random state (and random applied joint forces and body wrenches for the accelerations)
  OracleErrors compare_random_state(std::mt19937& rng);

  const Model& model() const { return model_; }
  const MujocoImport& import() const { return import_; }

 private:
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  Model model_;
  MujocoImport import_;
};

}  // namespace novaphy
