// The engine's loops over worlds, blocks, articulations and contacts on OpenMP threads.
#pragma once

#include <omp.h>

#include <algorithm>

namespace novaphy {

// f(i) for i in [0, count) on `threads` threads, then done() once on each thread. The first seven eighths
// of i go by a static schedule (thread t runs their t-th run: the same i, and their data in its caches,
// at every call); the last eighth is dealt out a few at a time to whichever thread is free, so that a
// thread the machine slows down does not keep the others waiting at the end. f must not depend on which
// thread runs i. One thread runs the loop without a parallel region (one costs more than a short loop),
// unless this runs inside another region, where only a region of its own numbers its thread 0,
// which per-thread scratch is indexed by. Each thread makes a Scope before its share and destroys it after
// done() (a mode the thread keeps while it runs f, such as SubnormalsAsZero: set once a call, not once an i)
struct NoScope {};
template <typename Scope = NoScope, typename F, typename Done>
void parallel_for(int threads, int count, F&& f, Done&& done) {
  if (threads > 1 || omp_in_parallel()) {
    const int team = std::max(threads, 1), bulk = count - count / 8;
    const int chunk = std::max(1, (count - bulk) / (4 * team));
#pragma omp parallel num_threads(team)
    {
      [[maybe_unused]] const Scope scope;
#pragma omp for schedule(static) nowait
      for (int i = 0; i < bulk; ++i) f(i);
#pragma omp for schedule(dynamic, chunk) nowait
      for (int i = bulk; i < count; ++i) f(i);
      done();
    }
  } else {
    [[maybe_unused]] const Scope scope;
    for (int i = 0; i < count; ++i) f(i);
    done();
  }
}

template <typename F>
void parallel_for(int threads, int count, F&& f) {
  parallel_for(threads, count, f, [] {});
}

}  // namespace novaphy
