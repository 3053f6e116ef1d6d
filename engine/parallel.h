// The engine's loops over worlds, blocks, articulations and contacts on OpenMP threads.
#pragma once

#include <omp.h>

#include <algorithm>

namespace novaphy {

// f(i) for i in [0, count) on `threads` threads, static schedule (thread t gets the t-th run of i), then
// done() once on each thread. One thread runs the loop without a parallel region (one costs more than a
// short loop: 0.35 us here), unless this runs inside another region, where only a region of its own
// numbers its thread 0, which per-thread scratch is indexed by
template <typename F, typename Done>
void parallel_for(int threads, int count, F&& f, Done&& done) {
  if (threads > 1 || omp_in_parallel()) {
#pragma omp parallel num_threads(std::max(threads, 1))
    {
#pragma omp for schedule(static) nowait
      for (int i = 0; i < count; ++i) f(i);
      done();
    }
  } else {
    for (int i = 0; i < count; ++i) f(i);
    done();
  }
}

template <typename F>
void parallel_for(int threads, int count, F&& f) {
  parallel_for(threads, count, f, [] {});
}

}  // namespace novaphy
