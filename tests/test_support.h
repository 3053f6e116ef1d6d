// Shared helpers of the C++ tests: random models and states, relative errors.
#pragma once

#include <random>
#include <string>

#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "kernels/convex.h"
#include "kernels/hull.h"

namespace novaphy::test {

// max |a - b| / max(1, max |b|)
Scalar relative_error(const MatX& a, const MatX& b);

// random joint_q (unit quaternions), joint_qd in [-2, 2], and applied wrenches body_f when asked
void randomize_state(const Model& model, State& state, std::mt19937& rng, bool wrenches);

// a random tree built directly with ModelBuilder: every joint type, rotated parent and child joint
// frames, offset centres of mass, full inertias; `roots` articulations of `links` links each
// `steps` steps of dt from model.state(), colliding each step, under `control`: the state after
State run_steps(const Model& model, const Control& control, int steps, Scalar dt,
                const SolverFeatherstoneSettings& settings = {});

Model random_builder_tree(std::mt19937& rng, int links, int roots = 1);

// a random tree written as MJCF text: hinge/slide/ball joints (several on one body, and refs),
// rotated body frames, offset joint anchors and centres of mass, full inertias; a free root if `floating`
std::string random_tree_mjcf(std::mt19937& rng, int bodies, bool floating);

// the hull of `points` and its arrays as the narrow phase reads them (view points into this object: no copies)
struct HullArrays {
  explicit HullArrays(const std::vector<Vec3>& points);
  HullArrays(const HullArrays&) = delete;
  HullArrays& operator=(const HullArrays&) = delete;
  ConvexHull hull;
  std::vector<Scalar> planes;  // [face][4]
  HullView view;
};

// the corners of a right prism over a regular n-gon about Y (circumradius r, half height h)
std::vector<Vec3> prism_points(int n, Scalar r, Scalar h);

// writes text to a fresh file in the temporary directory and returns its path
std::string write_temp_file(const std::string& name, const std::string& text);

}  // namespace novaphy::test
