// Writing around the caches. Output that the step writes once and does not read back (every body's
// pose and velocity) otherwise has each of its cache lines read in from memory before it is
// overwritten, and evicts the data the next block needs; a non-temporal store writes whole lines
// without reading them. stream_rows_from_lanes writes a block's lanes out as its worlds' rows, one
// after another, so: each vector of the destination gathered from the lanes, converted and stored
// (rather than transposing the lanes into a staged copy and streaming that). Its twin,
// stream_rows_from_lanes_reference, writes one number at a time with ordinary stores (and is what a target without
// gathers gets).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/lanes.h"

#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
#include <immintrin.h>
#endif

namespace novaphy {

inline void stream_fence() {
#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
  _mm_sfence();
#endif
}

// dst[l * count + k] = in[k][l] for k < count, l < lanes: lane l's row of count numbers, the rows one
// after another
template <typename T>
void stream_rows_from_lanes_reference(const Lanes<T>* in, int count, int lanes, double* dst) {
  for (int l = 0; l < lanes; ++l)
    for (int k = 0; k < count; ++k) dst[static_cast<std::ptrdiff_t>(l) * count + k] = in[k][l];
}

// stream_rows_from_lanes_reference's numbers, written around the caches where the machine has gathers
// (AVX2, AVX-512). The streamed stores are ordered after the thread's other stores only by a fence:
// stream_fence() once the thread's writes are done (before another thread may read them)
template <typename T>
void stream_rows_from_lanes(const Lanes<T>* in, int count, int lanes, double* dst) {
  const std::ptrdiff_t total = static_cast<std::ptrdiff_t>(count) * lanes;
  std::ptrdiff_t e = 0;
  auto one = [&](std::ptrdiff_t i) { dst[i] = in[i % count][i / count]; };
#if defined(__AVX2__)
  // eight numbers a turn from a 64-byte boundary of dst on: number e is in[k][l], e = l * count + k, at
  // the T k * kLanes<T> + l from in; the eight (k, l) step on by 8 = whole * count + part
  const T* base = reinterpret_cast<const T*>(in);
  for (; e < total && reinterpret_cast<std::uintptr_t>(dst + e) % 64 != 0; ++e) one(e);
  if (e + 8 <= total) {
    alignas(32) std::int32_t k0[8], l0[8];
    for (int j = 0; j < 8; ++j) {
      k0[j] = static_cast<std::int32_t>((e + j) % count);
      l0[j] = static_cast<std::int32_t>((e + j) / count);
    }
    __m256i k = _mm256_load_si256(reinterpret_cast<const __m256i*>(k0));
    __m256i l = _mm256_load_si256(reinterpret_cast<const __m256i*>(l0));
    const __m256i n = _mm256_set1_epi32(count), last = _mm256_set1_epi32(count - 1);
    const __m256i part = _mm256_set1_epi32(8 % count), whole = _mm256_set1_epi32(8 / count);
    const __m256i width = _mm256_set1_epi32(kLanes<T>);
    for (; e + 8 <= total; e += 8) {
      const __m256i at = _mm256_add_epi32(_mm256_mullo_epi32(k, width), l);
      if constexpr (sizeof(T) == sizeof(float)) {
        const __m256 x = _mm256_i32gather_ps(reinterpret_cast<const float*>(base), at, 4);
#if defined(__AVX512F__)
        _mm512_stream_pd(dst + e, _mm512_cvtps_pd(x));
#else
        _mm256_stream_pd(dst + e, _mm256_cvtps_pd(_mm256_castps256_ps128(x)));
        _mm256_stream_pd(dst + e + 4, _mm256_cvtps_pd(_mm256_extractf128_ps(x, 1)));
#endif
      } else {
        const double* b = reinterpret_cast<const double*>(base);
#if defined(__AVX512F__)
        _mm512_stream_pd(dst + e, _mm512_i32gather_pd(at, b, 8));
#else
        _mm256_stream_pd(dst + e, _mm256_i32gather_pd(b, _mm256_castsi256_si128(at), 8));
        _mm256_stream_pd(dst + e + 4, _mm256_i32gather_pd(b, _mm256_extracti128_si256(at, 1), 8));
#endif
      }
      k = _mm256_add_epi32(k, part);
      l = _mm256_add_epi32(l, whole);
      const __m256i wrap = _mm256_cmpgt_epi32(k, last);  // past the row's end: on to the next row
      k = _mm256_sub_epi32(k, _mm256_and_si256(wrap, n));
      l = _mm256_sub_epi32(l, wrap);
    }
  }
#endif
  for (; e < total; ++e) one(e);
}

}  // namespace novaphy
