// stream_copy: a copy whose destination is written around the caches. Output that the step writes
// once and does not read back (every body's pose and velocity) otherwise has each of its cache lines
// read in from memory before it is overwritten, and evicts the data the next block needs; a
// non-temporal store writes whole lines without reading them. std::copy is its portable twin (and
// what a target without these stores gets).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
#include <immintrin.h>
#endif

namespace novaphy {

// dst[0, n) = src[0, n). The streamed stores are ordered after the thread's other stores only by a
// fence: stream_fence() once the thread's copies are done (before another thread may read them)
inline void stream_copy(const double* src, double* dst, std::size_t n) {
#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
#if defined(__AVX512F__)
  constexpr std::size_t kWidth = 8;
#elif defined(__AVX__)
  constexpr std::size_t kWidth = 4;
#else
  constexpr std::size_t kWidth = 2;
#endif
  std::size_t i = 0;
  // the stores need an aligned address: the head up to it copied as usual
  for (; i < n && reinterpret_cast<std::uintptr_t>(dst + i) % (kWidth * sizeof(double)) != 0; ++i) dst[i] = src[i];
  for (; i + kWidth <= n; i += kWidth) {
#if defined(__AVX512F__)
    _mm512_stream_pd(dst + i, _mm512_loadu_pd(src + i));
#elif defined(__AVX__)
    _mm256_stream_pd(dst + i, _mm256_loadu_pd(src + i));
#else
    _mm_stream_pd(dst + i, _mm_loadu_pd(src + i));
#endif
  }
  for (; i < n; ++i) dst[i] = src[i];
#else
  std::copy(src, src + n, dst);
#endif
}

inline void stream_fence() {
#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
  _mm_sfence();
#endif
}

}  // namespace novaphy
