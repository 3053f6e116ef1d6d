#include "engine/solver/settings.h"

#include <type_traits>

#include "engine/model/error.h"

namespace novaphy {

namespace {

// a number in [lowest, highest] (NaN is not); a bound at the type's largest value is not named
template <typename T, typename Low, typename High>
void check_setting(const char* name, T value, Low lowest, High highest, const char* unit) {
  if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
    return;
  } else {
    if (value >= static_cast<T>(lowest) && value <= static_cast<T>(highest)) return;
    const char* space = *unit ? " " : "";
    const bool unbounded =
        static_cast<T>(highest) == std::numeric_limits<T>::max() ||
        (std::numeric_limits<T>::has_infinity && static_cast<T>(highest) == std::numeric_limits<T>::infinity());
    if (unbounded) fail("settings.", name, " must be >= ", lowest, space, unit, ", got ", value);
    fail("settings.", name, " must be in [", lowest, ", ", highest, "], got ", value);
  }
}

void check_policy(DivergencePolicy on_divergence) {
  if (static_cast<int>(on_divergence) < 0 || static_cast<int>(on_divergence) > 2)
    fail("settings.on_divergence must be Raise, Flag or Reset, got ", static_cast<int>(on_divergence));
}

}  // namespace

#define NOVAPHY_CHECK_SETTING(type, name, value, lowest, highest, unit, doc) \
  check_setting<type>(#name, name, lowest, highest, unit);

void SolverFeatherstoneSettings::check() const {
  check_policy(on_divergence);
  NOVAPHY_SOLVER_SETTINGS(NOVAPHY_CHECK_SETTING)
}

void SolverSemiImplicitSettings::check() const {
  check_policy(on_divergence);
  NOVAPHY_SEMI_IMPLICIT_SETTINGS(NOVAPHY_CHECK_SETTING)
}

void SolverXPBDSettings::check() const {
  check_policy(on_divergence);
  NOVAPHY_XPBD_SETTINGS(NOVAPHY_CHECK_SETTING)
}

#undef NOVAPHY_CHECK_SETTING

}  // namespace novaphy
