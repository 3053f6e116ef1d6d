#include "engine/model/finite_checks.h"

#include <omp.h>

#include <cmath>

#include "engine/model/error.h"

namespace novaphy {

void check_finite(Checked* arrays, int count, int threads) {
  std::uint64_t not_finite[kMostChecked] = {}, nonzero[kMostChecked] = {};
  auto scan = [&](int t, int teams) {
    for (int a = 0; a < count; ++a) {
      const std::vector<Scalar>& x = *arrays[a].x;
      const long n = static_cast<long>(x.size());
      std::uint64_t bad = 0, any = 0;
      scan_bits(x.data(), n * t / teams, n * (t + 1) / teams, &bad, &any);
      if (teams == 1) {
        not_finite[a] = bad;
        nonzero[a] = any;
        continue;
      }
#pragma omp atomic
      not_finite[a] |= bad;
#pragma omp atomic
      nonzero[a] |= any;
    }
  };
  long total = 0;
  for (int a = 0; a < count; ++a) total += static_cast<long>(arrays[a].x->size());
  if (threads > 1 && total >= 65536) {  // (a parallel region costs short arrays more than their scan)
#pragma omp parallel num_threads(threads)
    scan(omp_get_thread_num(), omp_get_num_threads());
  } else {
    scan(0, 1);
  }
  for (int a = 0; a < count; ++a) {
    arrays[a].nonzero = nonzero[a] != 0;
    if (not_finite[a] == 0) continue;
    const std::vector<Scalar>& x = *arrays[a].x;
    for (size_t k = 0; k < x.size(); ++k)
      if (!std::isfinite(x[k])) fail(arrays[a].name, "[", k, "] is not finite: ", x[k]);
  }
}

namespace {

// the state's arrays (body_f at kBodyF), then the control's, into `arrays` from `count`; each returns the
// new count
constexpr int kBodyF = 2;
int state_arrays(const State& state, Checked* arrays, int count) {
  arrays[count++] = {&state.joint_q, "joint_q"};
  arrays[count++] = {&state.joint_qd, "joint_qd"};
  arrays[count++] = {&state.body_f, "body_f"};
  return count;
}
int control_arrays(const Control& control, Checked* arrays, int count) {
#define NOVAPHY_CHECKED_CONTROL(T, name, n, width) arrays[count++] = {&control.name, #name};
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_CHECKED_CONTROL)
#undef NOVAPHY_CHECKED_CONTROL
  return count;
}
// whether a PD gain (joint_target_ke or joint_target_kd) is nonzero, among checked arrays
bool any_drive(const Control& control, const Checked* arrays, int count) {
  bool drive = false;
  for (int a = 0; a < count; ++a)
    drive |= (arrays[a].x == &control.joint_target_ke || arrays[a].x == &control.joint_target_kd) && arrays[a].nonzero;
  return drive;
}

}  // namespace

void check_finite_state(const State& state, bool* any_wrench, int threads) {
  Checked arrays[kMostChecked];
  const int count = state_arrays(state, arrays, 0);
  check_finite(arrays, count, threads);
  if (any_wrench) *any_wrench = arrays[kBodyF].nonzero;
}

void check_finite_control(const Control& control, bool* any_drive_out, int threads) {
  Checked arrays[kMostChecked];
  const int count = control_arrays(control, arrays, 0);
  check_finite(arrays, count, threads);
  if (any_drive_out) *any_drive_out = any_drive(control, arrays, count);
}

void check_finite_step(const State& state, const Control& control, bool* any_wrench, bool* any_drive_out, int threads) {
  Checked all[kMostChecked], arrays[kMostChecked], targets[kMostChecked];
  const int total = control_arrays(control, all, state_arrays(state, all, 0));
  int count = 0, target_count = 0;
  for (int a = 0; a < total; ++a) {
    const bool target = all[a].x == &control.joint_target_pos || all[a].x == &control.joint_target_vel;
    (target ? targets[target_count++] : arrays[count++]) = all[a];
  }
  check_finite(arrays, count, threads);
  *any_wrench = arrays[kBodyF].nonzero;
  *any_drive_out = any_drive(control, arrays, count);
  if (*any_drive_out) check_finite(targets, target_count, threads);
}

}  // namespace novaphy
