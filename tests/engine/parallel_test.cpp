#include "engine/parallel.h"

#include <gtest/gtest.h>

#include <mutex>
#include <utility>
#include <vector>

namespace novaphy {
namespace {

// the runs parallel_runs(threads, count) makes, each with the thread that ran it, and the team's size per done()
struct Runs {
  std::vector<std::pair<int, int>> runs;
  std::vector<int> thread;  // per i
  std::vector<int> done_team;
};

Runs record(int threads, int count) {
  Runs r;
  r.thread.assign(count, -1);
  std::mutex m;
  parallel_runs(
      threads, count,
      [&](int begin, int end) {
        const std::lock_guard<std::mutex> lock(m);
        r.runs.emplace_back(begin, end);
        for (int i = begin; i < end; ++i) r.thread[i] = omp_get_thread_num();
      },
      [&] {
        const std::lock_guard<std::mutex> lock(m);
        r.done_team.push_back(omp_get_num_threads());
      });
  return r;
}

TEST(ParallelRuns, CoverEachIOnceInRunsThenDoneOnceOnEachThread) {
  for (const int threads : {1, 2, 3, 4})
    for (const int count : {0, 1, 7, 8, 9, 64, 100, 1000}) {
      const Runs r = record(threads, count);
      std::vector<int> times(count, 0);
      for (const auto& [begin, end] : r.runs) {
        EXPECT_LE(0, begin);
        EXPECT_LE(end, count);
        for (int i = begin; i < end; ++i) ++times[i];
      }
      for (int i = 0; i < count; ++i) EXPECT_EQ(times[i], 1) << "i " << i << " of " << count << ", " << threads;
      ASSERT_FALSE(r.done_team.empty());
      EXPECT_EQ(static_cast<int>(r.done_team.size()), r.done_team.front()) << count << ", " << threads;
    }
}

TEST(ParallelRuns, EachThreadRunsTheSameFirstSevenEighthsAtEveryCall) {
  for (const int count : {9, 64, 1000}) {
    const Runs first = record(3, count), second = record(3, count);
    const int bulk = count - count / 8, n = first.done_team.front();
    for (int t = 0; t < n; ++t)
      for (int i = bulk * t / n; i < bulk * (t + 1) / n; ++i) {
        EXPECT_EQ(first.thread[i], t) << "i " << i << " of " << count;
        EXPECT_EQ(second.thread[i], t) << "i " << i << " of " << count;
      }
  }
}

TEST(ParallelRuns, TheLastEighthGoesInRunsOfHalfWhatIsLeftPerThreadDownToOne) {
  // a call of one thread inside another region runs on a team of that thread alone: the runs of its last eighth
  // are then dealt in turn, each half of what is left (a team of n: a 2n-th), the last ones a single i
  const int count = 800, bulk = count - count / 8;
  Runs r;
#pragma omp parallel num_threads(2)
#pragma omp single
  r = record(1, count);
  ASSERT_EQ(r.done_team, std::vector<int>{1});
  std::vector<std::pair<int, int>> expected = {{0, bulk}};
  for (int next = bulk; next < count;) {
    const int size = std::max(1, (count - next) / 2);
    expected.emplace_back(next, next + size);
    next += size;
  }
  EXPECT_EQ(r.runs, expected);
  EXPECT_EQ(r.runs.back(), std::make_pair(count - 1, count));
  // on more threads no run of the last eighth is longer than a 2n-th of it
  const Runs two = record(2, count);
  const int n = two.done_team.front();
  for (const auto& [begin, end] : two.runs)
    EXPECT_TRUE(begin < bulk || end - begin <= std::max(1, (count - bulk) / (2 * n))) << begin << " to " << end;
}

}  // namespace
}  // namespace novaphy
