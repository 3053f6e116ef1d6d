// Fixed joints welded away: the model the solver's kernels see, in which each body held to a parent
// body by a Fixed joint is merged into that parent's link (its mass, centre of mass and inertia
// added there), so a Fixed link costs nothing in FK, RNEA, CRBA or ABA. Coordinates and dofs keep
// their indices (a Fixed joint has none); bodies keep theirs.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

struct WeldedModel {
  Model model;                     // joints without the welded Fixed joints; merged link inertias (empty
                                   // when nothing is welded: the original model is the one to use)
  std::vector<int> link_body;      // per body: the body whose link carries it (itself unless welded)
  std::vector<Transform> offset;   // per body: its pose in link_body's frame (identity unless welded)
  std::vector<int> welded_bodies;  // the bodies merged into another
};

// Fixed joints whose parent is a body are welded (with weld false: none, the model as it is); a
// Fixed joint to the world stays (its body is static)
WeldedModel weld_fixed_joints(const Model& model, bool weld = true);

// the links' merged mass, centre of mass and inertia in w.model from model's bodies, for the worlds w with
// worlds[w] != 0 (empty: every world); w made by weld_fixed_joints(model) with something welded
void weld_masses(const Model& model, WeldedModel& w, const std::vector<std::uint8_t>& worlds);

}  // namespace novaphy
