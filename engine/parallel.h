// The engine's loops over worlds, blocks, articulations and contacts on OpenMP threads.
#pragma once

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>

namespace novaphy {

inline std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// wall time of whole calls (a solver's steps, a pipeline's collides) and of their parallel work, accumulated while
// counting is on; the rest of a call is the share more threads do not shorten
struct SerialSeconds {
  double step = 0;
  double parallel = 0;
  int steps = 0;
  double share() const { return step > 0 ? (step - parallel) / step : 0; }
};

// while one lives (and `on`), the wall time is added to *total in seconds
class ParallelTimer {
 public:
  ParallelTimer(bool on, double* total) : total_(on ? total : nullptr), start_(on ? now_ns() : 0) {}
  ~ParallelTimer() {
    if (total_) *total_ += 1e-9 * static_cast<double>(now_ns() - start_);
  }
  ParallelTimer(const ParallelTimer&) = delete;
  ParallelTimer& operator=(const ParallelTimer&) = delete;

 private:
  double* total_;
  std::int64_t start_;
};

// run(begin, end) over runs of i covering [0, count) on `threads` threads, then done() once on each thread. The
// first seven eighths of i go as one run a thread (thread t runs the t-th: the same i, and their data in its
// caches, at every call); the last eighth is dealt out to whichever thread is free, in runs that shrink as it
// runs out (a share of what is left, down to one i), so that a thread the machine slows down does not keep the
// others waiting at the end, and none starts a long run when little is left. run must not depend on which
// thread runs it. One thread runs [0, count) without a parallel region (one costs more than a short loop),
// unless this runs inside another region, where only a region of its own numbers its thread 0,
// which per-thread scratch is indexed by. Each thread makes a Scope before its share and destroys it after
// done() (a mode the thread keeps while it runs, such as SubnormalsAsZero: set once a call, not once an i)
struct NoScope {};

template <typename Scope = NoScope, typename Run, typename Done>
void parallel_runs(int threads, int count, Run&& run, Done&& done) {
  if (threads > 1 || omp_in_parallel()) {
    const int team = std::max(threads, 1), bulk = count - count / 8;
    std::atomic<int> next{bulk};
#pragma omp parallel num_threads(team)
    {
      [[maybe_unused]] const Scope scope;
      const long t = omp_get_thread_num(), n = omp_get_num_threads();
      run(static_cast<int>(bulk * t / n), static_cast<int>(bulk * (t + 1) / n));
      for (;;) {
        const int size = std::max(1, static_cast<int>((count - next.load(std::memory_order_relaxed)) / (2 * n)));
        const int begin = next.fetch_add(size, std::memory_order_relaxed);
        if (begin >= count) break;
        run(begin, std::min(count, begin + size));
      }
      done();
    }
  } else {
    [[maybe_unused]] const Scope scope;
    run(0, count);
    done();
  }
}

// f(i) for i in [0, count), as parallel_runs runs them
template <typename Scope = NoScope, typename F, typename Done>
void parallel_for(int threads, int count, F&& f, Done&& done) {
  parallel_runs<Scope>(
      threads, count,
      [&f](int begin, int end) {
        for (int i = begin; i < end; ++i) f(i);
      },
      done);
}

template <typename F>
void parallel_for(int threads, int count, F&& f) {
  parallel_for(threads, count, f, [] {});
}

}  // namespace novaphy
