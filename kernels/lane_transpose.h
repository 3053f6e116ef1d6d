// Moving a block's worlds between their rows of doubles (a world's coordinates, velocities, body
// poses: consecutive numbers) and lanes (one Lanes<T> per number, a world per lane). A tile of
// kChunk numbers from every world is loaded as whole vectors, converted to T, and transposed in
// registers by log2(kChunk) butterfly stages of two-vector shuffles; the way out is the same in
// reverse. Rows shorter than a tile, and the tail of a longer row, are moved by the last whole tile
// (overlapping the one before: the same numbers written twice) or, shorter than one, number by number.
// Their reference twins, lanes_from_rows_reference and rows_from_lanes_reference, move one number
// at a time; tests/kernels/lane_transpose_test.cpp finds both bit for bit equal (the conversions
// round the same).
#pragma once

#include <cstdint>
#include <cstring>
#include <utility>

#include "kernels/lanes.h"

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace novaphy {

namespace lane_detail {

// the doubles one vector holds, and the matching vectors of doubles and of kChunk T
inline constexpr int kChunk = kVectorBytes / static_cast<int>(sizeof(double));
typedef double Doubles __attribute__((vector_size(kVectorBytes)));
template <typename T>
struct Chunk;
template <>
struct Chunk<double> {
  typedef double type __attribute__((vector_size(kVectorBytes)));
};
template <>
struct Chunk<float> {
  typedef float type __attribute__((vector_size(kVectorBytes / 2)));
};

// one butterfly stage on a pair of rows a (bit s of its row clear) and b (set), within each group
// of kChunk lanes: the entries whose column has bit s set in a trade places with those of b whose
// column has it clear
template <typename V, int s, std::size_t... J>
inline void butterfly(V& a, V& b, std::index_sequence<J...>) {
  constexpr int W = sizeof...(J);
  const V lo = __builtin_shufflevector(a, b, ((J % kChunk) & s ? static_cast<int>(W + J - s) : static_cast<int>(J))...);
  const V hi = __builtin_shufflevector(a, b, ((J % kChunk) & s ? static_cast<int>(W + J) : static_cast<int>(J + s))...);
  a = lo, b = hi;
}

// rows r[0, kChunk) of kChunk entries (each group of kChunk lanes one square) transposed in place
template <typename V, int s = 1>
inline void transpose(V* r) {
  if constexpr (s < kChunk) {
    constexpr int W = sizeof(V) / sizeof(r[0][0]);
    for (int i = 0; i < kChunk; ++i)
      if ((i & s) == 0) butterfly<V, s>(r[i], r[i + s], std::make_index_sequence<W>());
    transpose<V, 2 * s>(r);
  }
}

// the kChunk doubles at p, as T
template <typename T>
inline typename Chunk<T>::type load_chunk(const double* p) {
  Doubles d;
  std::memcpy(&d, p, sizeof(d));
  return __builtin_convertvector(d, typename Chunk<T>::type);
}

// the kChunk T of x as doubles, and stored at p
template <typename T>
inline Doubles widen(const typename Chunk<T>::type& x) {
#if defined(__AVX512F__) && NOVAPHY_VECTOR_BYTES == 64
  if constexpr (sizeof(T) == sizeof(float)) {  // (GCC 12 widens eight floats in two halves)
    const __m512d d = _mm512_cvtps_pd(reinterpret_cast<const __m256&>(x));
    return reinterpret_cast<const Doubles&>(d);
  }
#endif
  return __builtin_convertvector(x, Doubles);
}
template <typename T>
inline void store_chunk(const typename Chunk<T>::type& x, double* p) {
  const Doubles d = widen<T>(x);
  std::memcpy(p, &d, sizeof(d));
}

// the row of kChunk T in group g of lanes v, and lanes v from two rows (float) or one (double)
template <typename T, std::size_t... J>
inline typename Chunk<T>::type group(const Lanes<T>& v, int g, std::index_sequence<J...>) {
  if constexpr (sizeof(T) == sizeof(double))
    return v;
  else if (g == 0)
    return __builtin_shufflevector(v, v, static_cast<int>(J)...);
  else
    return __builtin_shufflevector(v, v, static_cast<int>(J + kChunk)...);
}
template <typename T, std::size_t... J>
inline Lanes<T> join(const typename Chunk<T>::type* g, std::index_sequence<J...>) {
  if constexpr (sizeof(T) == sizeof(double))
    return g[0];
  else
    return __builtin_shufflevector(g[0], g[1], static_cast<int>(J)...);
}

}  // namespace lane_detail

// out[k][l] = T(row[l][k]) for k < count, every lane l
template <typename T>
void lanes_from_rows_reference(const double* const* row, int count, Lanes<T>* out) {
  for (int l = 0; l < kLanes<T>; ++l)
    for (int k = 0; k < count; ++k) out[k][l] = static_cast<T>(row[l][k]);
}

// row[l][k] = in[k][l] for k < count, the lanes l where `lanes` is set
template <typename T>
void rows_from_lanes_reference(const Lanes<T>* in, int count, const IntLanes<T>& lanes, double* const* row) {
  for (int l = 0; l < kLanes<T>; ++l)
    for (int k = 0; k < count && lanes[l]; ++k) row[l][k] = in[k][l];
}

// one number of every lane kept as kLanes<T> consecutive doubles: x[l] = T(p[l]), and p[l] = x[l] for the
// lanes set in `lanes` (whole vectors converted, the others' doubles blended back in; nothing to transpose)
template <typename T>
Lanes<T> lanes_from_doubles(const double* p) {
  using namespace lane_detail;
  typename Chunk<T>::type g[kLanes<T> / kChunk];
  for (int h = 0; h < kLanes<T> / kChunk; ++h) g[h] = load_chunk<T>(p + h * kChunk);
  return join<T>(g, std::make_index_sequence<kLanes<T>>());
}
template <typename T>
void doubles_from_lanes(const Lanes<T>& x, const IntLanes<T>& lanes, double* p) {
  using namespace lane_detail;
  typedef std::int64_t Mask __attribute__((vector_size(kVectorBytes)));
  for (int h = 0; h < kLanes<T> / kChunk; ++h) {
    Doubles old;
    std::memcpy(&old, p + h * kChunk, sizeof(old));
    const Doubles in = widen<T>(group<T>(x, h, std::make_index_sequence<kChunk>()));
    Mask on;
    for (int l = 0; l < kChunk; ++l) on[l] = lanes[h * kChunk + l];
    const Doubles out = on != 0 ? in : old;
    std::memcpy(p + h * kChunk, &out, sizeof(out));
  }
}

template <typename T>
void lanes_from_rows(const double* const* row, int count, Lanes<T>* out) {
  using namespace lane_detail;
  constexpr int kGroups = kLanes<T> / kChunk;
  if (count < kChunk) {
    lanes_from_rows_reference<T>(row, count, out);
    return;
  }
  for (int k0 = 0; k0 < count; k0 += kChunk) {
    const int k = k0 + kChunk <= count ? k0 : count - kChunk;  // the tail: the last whole tile
    Lanes<T> r[kChunk];
    for (int i = 0; i < kChunk; ++i) {
      typename Chunk<T>::type g[kGroups];
      for (int h = 0; h < kGroups; ++h) g[h] = load_chunk<T>(row[i + h * kChunk] + k);
      r[i] = join<T>(g, std::make_index_sequence<kLanes<T>>());
    }
    transpose(r);
    for (int i = 0; i < kChunk; ++i) out[k + i] = r[i];
  }
}

template <typename T>
void rows_from_lanes(const Lanes<T>* in, int count, const IntLanes<T>& lanes, double* const* row) {
  using namespace lane_detail;
  constexpr int kGroups = kLanes<T> / kChunk;
  if (count < kChunk) {
    rows_from_lanes_reference<T>(in, count, lanes, row);
    return;
  }
  for (int k0 = 0; k0 < count; k0 += kChunk) {
    const int k = k0 + kChunk <= count ? k0 : count - kChunk;
    Lanes<T> r[kChunk];
    for (int i = 0; i < kChunk; ++i) r[i] = in[k + i];
    transpose(r);
    for (int i = 0; i < kChunk; ++i)
      for (int h = 0; h < kGroups; ++h)
        if (lanes[i + h * kChunk])
          store_chunk<T>(group<T>(r[i], h, std::make_index_sequence<kChunk>()), row[i + h * kChunk] + k);
  }
}

}  // namespace novaphy
