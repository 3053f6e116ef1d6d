// MuJoCo's soft constraint (solref, solimp) as one row of the step's sweeps, for every row kind that has one (a
// contact's, contact_softness.h; a limit's, a dry friction's, an equality's). MuJoCo's rows satisfy
// J a + R f = aref with aref = -B v - K imp pos, R = (1 - imp) / imp * weight (weight: MuJoCo's diagApprox, the
// row's invweight0); times dt, with the impulse p = f dt, the step's J qd_out + R p = v + dt aref, v = J qd_in: a
// row of cfm R and target v + dt aref. A solref of (0, 0) is a hard row (the solver's erp and slop).
#pragma once

#include <algorithm>
#include <cmath>

#include "kernels/number.h"

namespace novaphy {

// whether a solref asks for a soft row: not (0, 0)
inline bool is_soft(const Scalar* solref) { return solref[0] != 0 || solref[1] != 0; }

// MuJoCo's impedance at a violation x (pos - margin), from solimp (dmin, dmax, width, midpoint, power), each
// clamped as MuJoCo clamps them where it reads them: dmin, dmax and midpoint into [1e-4, 0.9999], width to >= 0,
// power to >= 1 (the builder takes any finite solimp, as MuJoCo's compiler does)
inline Scalar impedance(const Scalar* solimp, Scalar x) {
  constexpr Scalar kMin = 1e-4, kMax = 0.9999;  // (MuJoCo's mjMINIMP, mjMAXIMP)
  const Scalar dmin = std::clamp(solimp[0], kMin, kMax), dmax = std::clamp(solimp[1], kMin, kMax);
  const Scalar width = solimp[2], mid = std::clamp(solimp[3], kMin, kMax), power = std::max(Scalar(1), solimp[4]);
  if (dmin == dmax || width <= 1e-15) return 0.5 * (dmin + dmax);
  const Scalar u = std::abs(x) / width;
  if (u >= 1) return dmax;
  // MuJoCo's u^p / mid^(p-1) below the midpoint and 1 - (1-u)^p / (1-mid)^(p-1) above, written as ratios <= 1
  // raised to p so that no power underflows to 0 / 0 (power 2, MuJoCo's default, without std::pow: this runs per
  // contact and step)
  const auto raise = [power](Scalar x) { return power == 2 ? x * x : std::pow(x, power); };
  const Scalar y = power == 1 ? u : u <= mid ? mid * raise(u / mid) : 1 - (1 - mid) * raise((1 - u) / (1 - mid));
  return dmin + y * (dmax - dmin);
}

// MuJoCo's K and B of a soft solref at dt: (time constant, damping ratio) with the time constant at least 2 dt
// (MuJoCo's refsafe), or (-stiffness, -damping), each over solimp's dmax
struct SoftReference {
  Scalar stiffness = 0, damping = 0;
};
inline SoftReference soft_reference(const Scalar* solref, const Scalar* solimp, Scalar dt) {
  const Scalar dmax = std::clamp(solimp[1], Scalar(1e-4), Scalar(0.9999));
  if (solref[0] > 0) {
    const Scalar tc = std::max(solref[0], 2 * dt);
    return {1 / std::max(Scalar(1e-15), dmax * dmax * tc * tc * solref[1] * solref[1]),
            2 / std::max(Scalar(1e-15), dmax * tc)};
  }
  return {-solref[0] / std::max(Scalar(1e-15), dmax * dmax), -solref[1] / std::max(Scalar(1e-15), dmax)};
}

// a soft row's cfm R = (1 - imp) / imp * weight at impedance imp (a contact's too, contact_softness.h)
inline Scalar soft_cfm(Scalar imp, Scalar weight) { return std::max(Scalar(1e-15), (1 - imp) / imp * weight); }

// a soft row's cfm and target
struct SoftRow {
  Scalar cfm = 0, target = 0;
};

// the soft row of a constraint violated by `pos` along the row (< 0 past a limit; an equality's error, 0 for dry
// friction: its row has no stiffness, MuJoCo's K = 0), its impedance read at `violation` (the constraint's: an
// equality's whole error; 0 for dry friction), its weight, its velocity v at the step's start
inline SoftRow soft_row(const Scalar* solref, const Scalar* solimp, Scalar weight, Scalar violation, Scalar pos,
                        Scalar v, Scalar dt) {
  const SoftReference k = soft_reference(solref, solimp, dt);
  const Scalar imp = impedance(solimp, violation);
  return {soft_cfm(imp, weight), v - dt * (k.damping * v + k.stiffness * imp * pos)};
}

// a soft row's numbers as the model keeps them per element: solref, solimp and weight (invweight0)
struct Softness {
  Scalar solref[2] = {}, solimp[5] = {}, weight = 0;
  bool soft() const { return is_soft(solref); }
};
inline Softness softness_of(const Scalar* solref, const Scalar* solimp, Scalar weight) {
  Softness s;
  std::copy_n(solref, 2, s.solref);
  std::copy_n(solimp, 5, s.solimp);
  s.weight = weight;
  return s;
}

}  // namespace novaphy
