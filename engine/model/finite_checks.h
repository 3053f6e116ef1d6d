// The finite checks of a step's or an evaluation's inputs: a State's and a Control's arrays scanned for inf and NaN
// (and for nonzero entries, which tell a step what it may skip), naming the first bad entry.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// arrays checked together: each one's name and, after the check, whether it has a nonzero entry
struct Checked {
  const std::vector<Scalar>* x = nullptr;
  const char* name = nullptr;
  bool nonzero = false;
};
constexpr int kMostChecked = 16;

// throws Error naming the first non-finite entry of the first array (in order) that has one; sets each
// array's nonzero. One pass over the bits (an exponent of all ones is inf or NaN; any bit but the
// sign's, a nonzero), vectorised; on `threads` threads when the arrays are long, all of them in one
// parallel region (each thread its share of every array); the search only on failure
void check_finite(Checked* arrays, int count, int threads);

// one pass over the bits of x[begin, end): ORs into *bad a nonzero where an entry is inf or NaN (an exponent of all
// ones) and into *nonzero one where an entry is not +-0 (any bit but the sign's); vectorises
inline void scan_bits(const Scalar* x, long begin, long end, std::uint64_t* bad, std::uint64_t* nonzero) {
  static_assert(sizeof(Scalar) == sizeof(std::uint64_t));
  constexpr std::uint64_t kExponent = 0x7ff0000000000000;
  std::uint64_t b = 0, any = 0;
  for (long k = begin; k < end; ++k) {
    std::uint64_t bits;
    std::memcpy(&bits, &x[k], sizeof(bits));
    b |= (bits & kExponent) == kExponent;
    any |= bits << 1;
  }
  *bad |= b;
  *nonzero |= any;
}

// throws Error naming the first non-finite entry of state.joint_q / joint_qd / body_f; any_wrench
// (when given) is set to whether body_f holds a nonzero entry
void check_finite_state(const State& state, bool* any_wrench = nullptr, int threads = 1);
// throws Error naming the first non-finite entry of any control array
// any_drive (when given) is set to whether a PD gain (joint_target_ke or joint_target_kd) is nonzero
void check_finite_control(const Control& control, bool* any_drive = nullptr, int threads = 1);
// both, in that order, in one pass (one parallel region on `threads` threads), except the PD targets
// (joint_target_pos, joint_target_vel): a step reads them only where a gain is nonzero, so they are checked
// only when any_drive is set, in a second pass
void check_finite_step(const State& state, const Control& control, bool* any_wrench, bool* any_drive, int threads = 1);

}  // namespace novaphy
