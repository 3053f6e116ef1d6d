// The checks ModelBuilder's calls make of their arguments, each failing with an Error that names the
// item ("joint 3 ('knee')") and the argument. Internal to the builder's files (builder*.cpp).
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "engine/model/builder.h"
#include "engine/model/error.h"
#include "kernels/spatial.h"

namespace novaphy {

inline std::string label(const char* kind, int index, const std::string& name) {
  std::string s = std::string(kind) + " " + std::to_string(index);
  if (!name.empty()) s += " ('" + name + "')";
  return s;
}

inline void check_finite(const std::string& item, const char* what, Scalar x) {
  if (!std::isfinite(x)) fail(item, ": ", what, " is not finite: ", x);
}

inline void check_finite(const std::string& item, const char* what, const Vec3& x) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(x[k])) fail(item, ": ", what, "[", k, "] is not finite: ", x[k]);
}

inline Transform checked_transform(const std::string& item, const char* what, const Transform& T) {
  check_finite(item, what, T.p);
  const Eigen::Vector4d q = T.q.coeffs();
  for (int k = 0; k < 4; ++k)
    if (!std::isfinite(q[k])) fail(item, ": ", what, " rotation[", k, "] is not finite: ", q[k]);
  if (q.norm() < 1e-9) fail(item, ": ", what, " rotation quaternion has zero length");
  Transform out = T;
  out.q.normalize();
  return out;
}

inline void check_nonnegative(const std::string& item, const char* what, Scalar x) {
  if (!(x >= 0) || !std::isfinite(x)) fail(item, ": ", what, " must be finite and >= 0, got ", x);
}

inline void check_positive(const std::string& item, const char* what, Scalar x) {
  if (!(x > 0) || !std::isfinite(x)) fail(item, ": ", what, " must be finite and > 0, got ", x);
}

// a range [lower, upper] (infinite ends allowed, NaN not)
inline void check_range(const std::string& item, const char* what, Scalar lower, Scalar upper) {
  if (std::isnan(lower) || std::isnan(upper) || lower > upper)
    fail(item, ": ", what, " must satisfy lower <= upper, got [", lower, ", ", upper, "]");
}

// rigid_body_problem's common case, without a message: every value finite, mass > 0, the inertia symmetric, I and
// C = tr(I) / 2 - I (the mass's second moments, whose smallest eigenvalue c is half the triangle inequality's slack:
// I_a + I_b - I_c = 2 c; shifted by -1e-9 / 2 times I's largest diagonal entry, at most its largest principal moment:
// never looser than rigid_body_problem's eigenvalue test) positive definite by their leading minors. False says
// only that rigid_body_problem must decide
inline bool rigid_body_clearly_fine(const RigidBody& body) {
  if (!(body.mass > 0) || !std::isfinite(body.mass) || !body.com.allFinite() || !body.inertia.allFinite()) return false;
  const Scalar scale = body.inertia.cwiseAbs().maxCoeff();
  if ((body.inertia - body.inertia.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Mat3 C =
      Mat3::Identity() * (body.inertia.trace() / 2 + 0.5e-9 * body.inertia.diagonal().maxCoeff()) - body.inertia;
  auto positive_definite = [](const Mat3& A) {  // (Sylvester: the leading minors)
    return A(0, 0) > 0 && A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0) > 0 && A.determinant() > 0;
  };
  return positive_definite(body.inertia) && positive_definite(C);
}

// what is wrong with a body's mass, centre of mass and inertia ("" where nothing is): each finite; mass > 0 (or 0
// with zero inertia where allow_massless) and an inertia a real body has (symmetric, positive definite, the triangle
// inequality)
inline std::string rigid_body_problem(const RigidBody& body, bool allow_massless) {
  if (rigid_body_clearly_fine(body)) return "";
  auto problem = [](const auto&... parts) {
    std::ostringstream os;
    os.precision(17);
    (os << ... << parts);
    return os.str();
  };
  if (!std::isfinite(body.mass)) return problem("mass is not finite: ", body.mass);
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(body.com[k])) return problem("com[", k, "] is not finite: ", body.com[k]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(body.inertia(r, c)))
        return problem("inertia(", r, ", ", c, ") is not finite: ", body.inertia(r, c));
  if (allow_massless && body.mass == 0) return body.inertia.norm() != 0 ? "a massless link must have zero inertia" : "";
  if (!(body.mass > 0)) return problem("mass must be > 0, got ", body.mass);
  const Scalar scale = body.inertia.cwiseAbs().maxCoeff();
  if ((body.inertia - body.inertia.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return "inertia is not symmetric";
  // not clearly fine: the principal moments decide and name the problem
  const Vec3 eig = Eigen::SelfAdjointEigenSolver<Mat3>(body.inertia, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(eig[0] > 0)) return problem("inertia is not positive definite (smallest principal moment ", eig[0], ")");
  // principal moments of a real body: each at most the sum of the other two
  if (eig[2] > eig[0] + eig[1] + 1e-9 * eig[2])
    return problem("inertia violates the triangle inequality (principal moments ", eig[0], ", ", eig[1], ", ", eig[2],
                   ")");
  return "";
}

inline void check_rigid_body(const std::string& item, const RigidBody& body, bool allow_massless) {
  const std::string problem = rigid_body_problem(body, allow_massless);
  if (!problem.empty()) fail(item, ": ", problem);
}

inline void check_actuator(const std::string& item, const ActuatorOptions& options) {
  check_finite(item, "gear", options.gear);
  check_finite(item, "gain", options.gain);
  for (int k = 0; k < 3; ++k) check_finite(item, "bias", options.bias[k]);
  check_range(item, "control range", options.ctrl_lower, options.ctrl_upper);
  check_range(item, "force range", options.force_lower, options.force_upper);
}

// a solref and a solimp as MuJoCo takes them: solref (0, 0) for a hard row, and any finite solimp (MuJoCo accepts
// them and clamps each use: impedance, engine/solver/parts/soft_row.h); `what` names them ("limit_solref")
inline void check_solref(const std::string& item, const char* what, const std::array<Scalar, 2>& solref) {
  const Scalar t = solref[0], r = solref[1];
  if (!((t == 0 && r == 0) || (t > 0 && r > 0 && std::isfinite(t) && std::isfinite(r)) ||
        (t < 0 && r <= 0 && std::isfinite(t) && std::isfinite(r))))
    fail(item, ": ", what,
         " must be (time constant > 0, damping ratio > 0), (-stiffness < 0, -damping <= 0) or (0, 0) for a hard row, "
         "got (",
         t, ", ", r, ")");
}
inline void check_solimp(const std::string& item, const char* what, const std::array<Scalar, 5>& i) {
  if (!std::all_of(i.begin(), i.end(), [](Scalar x) { return std::isfinite(x); }))
    fail(item, ": ", what, " must be five finite numbers (dmin, dmax, width, midpoint, power), got (", i[0], ", ", i[1],
         ", ", i[2], ", ", i[3], ", ", i[4], ")");
}

// a shape's solref, solimp, solmix, margin and gap as MuJoCo takes them (ShapeOptions)
inline void check_softness(const std::string& item, const ShapeOptions& o) {
  check_solref(item, "solref", o.solref);
  check_solimp(item, "solimp", o.solimp);
  check_nonnegative(item, "solmix", o.solmix);
  check_nonnegative(item, "margin", o.margin);
  check_nonnegative(item, "gap", o.gap);
}

}  // namespace novaphy
