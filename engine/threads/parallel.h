// The engine's loops over worlds, blocks, articulations and contacts on OpenMP threads, and how many threads
// they wake while other processes keep the cores busy.
#pragma once

#include <omp.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>

namespace novaphy {

inline std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// the CPU time the calling thread has run, in ns
inline std::int64_t thread_cpu_ns() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
}

// the time, in ns since boot, that some runnable thread of this machine has waited for a core (the "some" total
// of Linux's CPU pressure, /proc/pressure/cpu); -1 where the system does not tell
inline std::int64_t cpu_pressure_ns() {
  std::FILE* file = std::fopen("/proc/pressure/cpu", "r");
  if (!file) return -1;
  unsigned long long total = 0;
  const int read = std::fscanf(file, "some avg10=%*f avg60=%*f avg300=%*f total=%llu", &total);
  std::fclose(file);
  return read == 1 ? static_cast<std::int64_t>(total) * 1000 : -1;
}

// Whether a region's team pays on this machine now. OpenMP's threads wait at a region's end by spinning, so while
// other processes keep the cores busy a waiting thread holds a core its partner needs, and a thread off its core
// holds the others at the barrier: N threads can step slower than one. The regions start on one thread. Now and
// then a window of regions is timed: the CPU time their threads spent on the work over the regions' wall time, the
// cores' worth of work a region gets done a second (its rate); one thread's window, then the team's. A team that
// does at least as well as one thread is kept, and measured again now and then; one that falls below nine tenths of
// one thread's rate hands its regions back to one thread, and the team is tried again after a wait that doubles each
// time it loses. A try costs: on busy cores a team's region stalls for a time slice of the scheduler, so
//  - a team window ends as soon as its regions, past kClearLossWall of wall time, get less than half of one
//    thread's rate (a losing try costs about one such region, not a window of them);
//  - no try is made while threads waited for a core for more than kBusy of the wait (the machine's CPU pressure):
//    the wait doubles as if the team had lost, and only the longest wait ends in a try whatever the pressure.
// Which threads run what never changes a result (the engine's loops give the same bits on any team)
class TeamChoice {
 public:
  // times in ns: a window is at least kWindow of measured regions' wall time and kWindowRegions regions; a team
  // kept is measured again kPeriod after its last window; the first try waits kFirstLook; a team handed over is
  // tried again after kFirstWait, doubling up to kLongestWait while it loses
  static constexpr std::int64_t kWindow = 10'000'000, kPeriod = 200'000'000, kFirstLook = 20'000'000;
  static constexpr std::int64_t kFirstWait = 100'000'000, kLongestWait = 3'200'000'000;
  static constexpr std::int64_t kClearLossWall = 1'000'000;
  static constexpr int kWindowRegions = 4;
  static constexpr double kClearLoss = 0.5, kBusy = 0.25;

  // the threads a region asking for `requested` runs on, and whether its times go to record()
  struct Plan {
    int threads = 1;
    bool measured = false;
  };

  // pressure: the machine's CPU pressure, as cpu_pressure_ns()
  explicit TeamChoice(std::int64_t (*pressure)() = cpu_pressure_ns) : pressure_(pressure) {}

  Plan plan(int requested, std::int64_t now) {
    if (requested <= 1) return {1, false};
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!adapt_) return {requested, false};
    if (phase_ == Phase::Wait) {
      if (now < wait_until_) return {one_ ? 1 : requested, false};
      if (one_ && !try_team(now)) return {1, false};
      phase_ = Phase::Measure;
    }
    return {team() ? requested : 1, true};
  }

  // a measured region's wall time and the CPU time its threads spent on its work, all of them together (ns);
  // whether it closed a window
  bool record(const Plan& plan, std::int64_t wall, std::int64_t cpu, std::int64_t now) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (phase_ == Phase::Wait || (plan.threads > 1) != team()) return false;  // planned before the last one closed
    wall_ += wall;
    cpu_ += cpu;
    const double rate = static_cast<double>(cpu_) / static_cast<double>(wall_);
    const bool clear_loss = team() && wall_ >= kClearLossWall && rate < kClearLoss * one_rate_;
    if (!clear_loss && (++regions_ < kWindowRegions || wall_ < kWindow)) return false;
    wall_ = cpu_ = 0;
    regions_ = 0;
    if (phase_ == Phase::Measure && one_) {  // one thread's rate, then the team's at once
      one_rate_ = rate;
      phase_ = Phase::Probe;
      return true;
    }
    const bool team_pays = phase_ == Phase::Probe ? rate >= one_rate_ : rate >= 0.9 * one_rate_;
    if (team_pays) {
      one_ = false;
      wait_ = kFirstWait;
      wait_until_ = now + kPeriod;
    } else {
      one_ = true;
      wait(now);
    }
    phase_ = Phase::Wait;
    return true;
  }

  // the threads a region that is not measured runs on (the collision pipeline's)
  int threads(int requested) {
    const std::lock_guard<std::mutex> lock(mutex_);
    return !adapt_ || requested <= 1 || team() ? requested : 1;
  }

  // off: every region runs on the threads it asks for (tests of which thread runs what)
  void adapt(bool on) {
    const std::lock_guard<std::mutex> lock(mutex_);
    adapt_ = on;
  }

 private:
  enum class Phase { Wait, Measure, Probe };
  bool team() const { return !one_ || phase_ == Phase::Probe; }

  // one thread from now for the next wait, the CPU pressure looked at as it starts
  void wait(std::int64_t now) {
    wait_until_ = now + wait_;
    wait_ = std::min(2 * wait_, kLongestWait);
    pressure_at_ = pressure_();
    looked_at_ = now;
  }

  // (one thread, its wait over) whether the team is tried now; else the next wait
  bool try_team(std::int64_t now) {
    if (looked_at_ < 0) {  // the first call: a short look at the pressure first
      pressure_at_ = pressure_();
      looked_at_ = now;
      wait_until_ = now + kFirstLook;
      return false;
    }
    const std::int64_t pressure = pressure_(), waited = now - looked_at_;
    const bool busy = pressure >= 0 && pressure_at_ >= 0 &&
                      static_cast<double>(pressure - pressure_at_) > kBusy * static_cast<double>(waited);
    if (!busy || waited >= kLongestWait) return true;
    wait(now);
    return false;
  }

  std::int64_t (*pressure_)();
  std::mutex mutex_;
  bool adapt_ = true;
  bool one_ = true;                  // regions run on one thread (else on the team they ask for)
  Phase phase_ = Phase::Wait;        // until the first call's look at the pressure
  std::int64_t wait_until_ = 0;      // (Wait) when the next window starts
  std::int64_t wait_ = kFirstWait;   // the next wait: how long one thread runs before the team is tried again
  std::int64_t pressure_at_ = -1;    // the CPU pressure when the wait began
  std::int64_t looked_at_ = -1;      // when it began
  double one_rate_ = 1;              // one thread's rate, last measured
  std::int64_t wall_ = 0, cpu_ = 0;  // the window so far
  int regions_ = 0;
};

// the process's choice, which every parallel_runs and the collision pipeline follow
inline TeamChoice& team_choice() {
  static TeamChoice choice;
  return choice;
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

// run(begin, end) over runs of i covering [0, count) on `threads` threads (one while team_choice() finds the team
// does not pay), then done() once on each thread. The
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
  const bool nested = omp_in_parallel();
  const TeamChoice::Plan plan = nested ? TeamChoice::Plan{threads, false} : team_choice().plan(threads, now_ns());
  const std::int64_t start = plan.measured ? now_ns() : 0;
  std::atomic<std::int64_t> cpu{0};
  if (plan.threads > 1 || nested) {
    const int team = std::max(plan.threads, 1), bulk = count - count / 8;
    std::atomic<int> next{bulk};
#pragma omp parallel num_threads(team)
    {
      const std::int64_t cpu_start = plan.measured ? thread_cpu_ns() : 0;
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
      if (plan.measured) cpu.fetch_add(thread_cpu_ns() - cpu_start, std::memory_order_relaxed);
    }
  } else {
    const std::int64_t cpu_start = plan.measured ? thread_cpu_ns() : 0;
    {
      [[maybe_unused]] const Scope scope;
      run(0, count);
      done();
    }
    if (plan.measured) cpu.fetch_add(thread_cpu_ns() - cpu_start, std::memory_order_relaxed);
  }
  if (!plan.measured) return;
  const std::int64_t end = now_ns();
  team_choice().record(plan, end - start, cpu.load(std::memory_order_relaxed), end);
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
