// Lanes<T>: one SIMD register of T, one world per lane (the compiler's generic vector type, so
// the same arithmetic compiles to AVX-512, AVX2 or SSE2 for whatever -march the build names).
// Kernels on lanes do the same operation on every lane; nothing here looks across lanes, so a
// world's result does not depend on which lane or block it sits in.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace novaphy {

// the target's widest vectors; the lanes are as wide unless the build names narrower ones
#if defined(__AVX512F__)
#define NOVAPHY_TARGET_VECTOR_BYTES 64
#elif defined(__AVX__)
#define NOVAPHY_TARGET_VECTOR_BYTES 32
#else
#define NOVAPHY_TARGET_VECTOR_BYTES 16
#endif
#ifndef NOVAPHY_VECTOR_BYTES
#define NOVAPHY_VECTOR_BYTES NOVAPHY_TARGET_VECTOR_BYTES
#endif
// an installed NovaPhy defines the target width and -march its library was compiled for (CMakeLists.txt):
// code compiled for a target with other vectors would lay out the lanes and Eigen's types unlike the library
#ifdef NOVAPHY_LIBRARY_TARGET_VECTOR_BYTES
#ifndef NOVAPHY_LIBRARY_ARCH
#define NOVAPHY_LIBRARY_ARCH "the library's -march"
#endif
static_assert(NOVAPHY_TARGET_VECTOR_BYTES == NOVAPHY_LIBRARY_TARGET_VECTOR_BYTES,
              "NovaPhy's library was compiled with " NOVAPHY_LIBRARY_ARCH
              ", for a target whose vectors differ in width "
              "from this compilation's: compile the code that includes NovaPhy's headers with the same -march (the "
              "novaphy:: CMake targets pass it)");
#endif

inline constexpr int kVectorBytes = NOVAPHY_VECTOR_BYTES;
template <typename T>
inline constexpr int kLanes = kVectorBytes / static_cast<int>(sizeof(T));

// (plain typedefs: an attribute on an alias template drops const from pointers to it in GCC 12)
template <typename T>
struct LaneTypes;
template <>
struct LaneTypes<float> {
  typedef float type __attribute__((vector_size(NOVAPHY_VECTOR_BYTES)));
  typedef std::int32_t mask __attribute__((vector_size(NOVAPHY_VECTOR_BYTES)));
};
template <>
struct LaneTypes<double> {
  typedef double type __attribute__((vector_size(NOVAPHY_VECTOR_BYTES)));
  typedef std::int64_t mask __attribute__((vector_size(NOVAPHY_VECTOR_BYTES)));
};
template <typename T>
using Lanes = typename LaneTypes<T>::type;
// the signed integers of T's width: comparison masks and quadrant numbers
template <typename T>
using IntLanes = typename LaneTypes<T>::mask;

// true when some lane of the mask m is set: one test of the whole register where the machine has one
// (AVX-512's into a mask register, AVX's vptest), else read as words (a vector compare and a branch per
// lane would cost more than the test it guards)
template <typename T>
inline bool any_lane(const IntLanes<T>& m) {
#if defined(__AVX512F__)
  if constexpr (sizeof(m) == 64) {
    __m512i x;
    std::memcpy(&x, &m, sizeof(x));
    return _mm512_test_epi64_mask(x, x) != 0;
  }
#endif
#if defined(__AVX__)
  if constexpr (sizeof(m) == 32) {
    __m256i x;
    std::memcpy(&x, &m, sizeof(x));
    return !_mm256_testz_si256(x, x);
  }
#endif
  std::uint64_t x[sizeof(m) / 8], any = 0;
  std::memcpy(x, &m, sizeof(m));
  for (const std::uint64_t word : x) any |= word;
  return any != 0;
}

// While one lives, the calling thread's vector arithmetic treats subnormal inputs as zero and flushes
// subnormal results to zero (x86's MXCSR DAZ and FTZ; elsewhere nothing changes); the mode it found is
// restored when it ends. The float32 blocks run under it: an operand below FLT_MIN (1.2e-38) takes the
// core a slow microcode path per operation, and a robot near rest makes such operands every step (the
// squares and products of velocities of 1e-26 to 1e-19)
class SubnormalsAsZero {
 public:
#if defined(__SSE__)
  SubnormalsAsZero() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushToZero | kDenormalsAreZero); }
  ~SubnormalsAsZero() { _mm_setcsr(saved_); }
#else
  SubnormalsAsZero() = default;
#endif
  SubnormalsAsZero(const SubnormalsAsZero&) = delete;
  SubnormalsAsZero& operator=(const SubnormalsAsZero&) = delete;

 private:
#if defined(__SSE__)
  static constexpr unsigned kFlushToZero = 0x8000, kDenormalsAreZero = 0x0040;
  unsigned saved_;
#endif
};

// sqrt and nearbyint of every lane in one instruction of the target's width where it has one (a loop the
// compiler vectorises may split a 64-byte register into halves through the stack, which stalls the load that
// joins them); the same bits either way (the masked roundscale: the unmasked one reads an undefined register
// GCC 12 warns of)
template <typename T>
inline Lanes<T> lane_sqrt(Lanes<T> x) {
  constexpr bool single = sizeof(T) == 4;
#if defined(__AVX512F__)
  if constexpr (sizeof(x) == 64) {
    if constexpr (single) return reinterpret_cast<Lanes<T>>(_mm512_sqrt_ps(reinterpret_cast<__m512>(x)));
    if constexpr (!single) return reinterpret_cast<Lanes<T>>(_mm512_sqrt_pd(reinterpret_cast<__m512d>(x)));
  }
#endif
#if defined(__AVX__)
  if constexpr (sizeof(x) == 32) {
    if constexpr (single) return reinterpret_cast<Lanes<T>>(_mm256_sqrt_ps(reinterpret_cast<__m256>(x)));
    if constexpr (!single) return reinterpret_cast<Lanes<T>>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(x)));
  }
#endif
  Lanes<T> r;
  for (int l = 0; l < kLanes<T>; ++l) r[l] = std::sqrt(x[l]);
  return r;
}

template <typename T>
inline Lanes<T> lane_abs(Lanes<T> x) {
  return x < 0 ? -x : x;
}

template <typename T>
inline Lanes<T> lane_round(Lanes<T> x) {
  constexpr bool single = sizeof(T) == 4;
#if defined(__AVX__)
  constexpr int kNearest = _MM_FROUND_CUR_DIRECTION | _MM_FROUND_NO_EXC;
#endif
#if defined(__AVX512F__)
  if constexpr (sizeof(x) == 64) {
    if constexpr (single)
      return reinterpret_cast<Lanes<T>>(
          _mm512_mask_roundscale_ps(reinterpret_cast<__m512>(x), 0xffff, reinterpret_cast<__m512>(x), kNearest));
    if constexpr (!single)
      return reinterpret_cast<Lanes<T>>(
          _mm512_mask_roundscale_pd(reinterpret_cast<__m512d>(x), 0xff, reinterpret_cast<__m512d>(x), kNearest));
  }
#endif
#if defined(__AVX__)
  if constexpr (sizeof(x) == 32) {
    if constexpr (single) return reinterpret_cast<Lanes<T>>(_mm256_round_ps(reinterpret_cast<__m256>(x), kNearest));
    if constexpr (!single) return reinterpret_cast<Lanes<T>>(_mm256_round_pd(reinterpret_cast<__m256d>(x), kNearest));
  }
#endif
  Lanes<T> r;
  for (int l = 0; l < kLanes<T>; ++l) r[l] = std::nearbyint(x[l]);
  return r;
}

// sin and cos of every lane: Cody-Waite reduction by pi/2 (three-part constant) and minimax
// polynomials on [-pi/4, pi/4] (Moshier's Cephes coefficients). Within one epsilon of std::sin/cos
// for |x| < 1e4 (double) and |x| < 1e3 (float); tests/kernels/batch_test.cpp measures it.
template <typename T>
inline void lane_sincos(Lanes<T> x, Lanes<T>* s, Lanes<T>* c) {
  using V = Lanes<T>;
  const V k = lane_round<T>(x * T(0.63661977236758134308));
  V r, z, ps, pc;
  if constexpr (sizeof(T) == 8) {
    r = ((x - k * 1.57079625129699707031) - k * 7.54978941586159635336e-8) - k * 5.39030285815811905290e-15;
    z = r * r;
    ps = ((((1.58962301576546568060e-10 * z - 2.50507477628578072866e-8) * z + 2.75573136213857245213e-6) * z -
           1.98412698295895385996e-4) *
              z +
          8.33333333332211858878e-3) *
             z -
         1.66666666666666307295e-1;
    pc = ((((-1.13585365213876817300e-11 * z + 2.08757008419747316778e-9) * z - 2.75573141792967388112e-7) * z +
           2.48015872888517045348e-5) *
              z -
          1.38888888888730564116e-3) *
             z +
         4.16666666666665929218e-2;
  } else {
    r = ((x - k * 1.5703125f) - k * 4.837512969970703125e-4f) - k * 7.54978995489188216e-8f;
    z = r * r;
    ps = (-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f;
    pc = (2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f;
  }
  const V sin_r = r + r * z * ps;
  const V cos_r = (1 - T(0.5) * z) + z * z * pc;
  const IntLanes<T> quadrant = __builtin_convertvector(k, IntLanes<T>);
  const IntLanes<T> swap = (quadrant & 1) != 0;
  const V sin_q = swap ? cos_r : sin_r;
  const V cos_q = swap ? sin_r : cos_r;
  *s = (quadrant & 2) != 0 ? -sin_q : sin_q;
  *c = ((quadrant + 1) & 2) != 0 ? -cos_q : cos_q;
}

}  // namespace novaphy
