#include "engine/threads/parallel.h"

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

// the runs below on the threads asked for, whatever the machine's load
class ParallelRuns : public ::testing::Test {
 protected:
  void SetUp() override { team_choice().adapt(false); }
  void TearDown() override { team_choice().adapt(true); }
};

TEST_F(ParallelRuns, CoverEachIOnceInRunsThenDoneOnceOnEachThread) {
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

TEST_F(ParallelRuns, EachThreadRunsTheSameFirstSevenEighthsAtEveryCall) {
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

TEST_F(ParallelRuns, TheLastEighthGoesInRunsOfHalfWhatIsLeftPerThreadDownToOne) {
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

std::pair<int, bool> of(const TeamChoice::Plan& plan) { return {plan.threads, plan.measured}; }

// a machine's CPU pressure for TeamChoice: the time threads waited for a core grows by `busy` of the clock's time
double busy = 0;
std::int64_t pressure_at = 0;
std::int64_t pressure_ns() { return pressure_at; }
void advance(std::int64_t& now, std::int64_t ns) {
  now += ns;
  pressure_at += static_cast<std::int64_t>(busy * static_cast<double>(ns));
}

// regions until `windows` windows close, from time `now` (ns), each region 5 ms long and doing `rate` cores' worth
// of work a second on one thread or on the team; returns the time after them, and the regions in *regions
std::int64_t run_windows(TeamChoice& choice, int windows, int requested, double one_rate, double team_rate,
                         std::int64_t now, int* regions = nullptr) {
  const std::int64_t region = 5'000'000;
  int closed = 0, count = 0;
  while (closed < windows) {
    const TeamChoice::Plan plan = choice.plan(requested, now);
    EXPECT_TRUE(plan.measured);
    const double rate = plan.threads > 1 ? team_rate : one_rate;
    advance(now, region);
    closed += choice.record(plan, region, static_cast<std::int64_t>(rate * region), now) ? 1 : 0;
    ++count;
  }
  if (regions) *regions = count;
  return now;
}

class TeamChoiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    busy = 0;
    pressure_at = 0;
  }

  // the first call looks at the pressure, on one thread, for kFirstLook; returns the time after
  std::int64_t start(TeamChoice& choice) {
    EXPECT_EQ(of(choice.plan(2, 0)), std::make_pair(1, false));
    std::int64_t now = 0;
    advance(now, TeamChoice::kFirstLook - 1);
    EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, false));
    advance(now, 1);
    return now;
  }
};

TEST_F(TeamChoiceTest, KeepsATeamThatGetsMoreThanACoreOfWorkDone) {
  TeamChoice choice(pressure_ns);
  EXPECT_EQ(of(choice.plan(1, 0)), std::make_pair(1, false));
  std::int64_t now = start(choice);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));  // one thread's window, then the team's
  now = run_windows(choice, 1, 2, 1.0, 1.9, now);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, true));
  now = run_windows(choice, 1, 2, 1.0, 1.9, now);
  // measured again only after a period, on the team all along
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, false));
  EXPECT_FALSE(choice.plan(2, now + TeamChoice::kPeriod - 1).measured);
  EXPECT_EQ(choice.threads(2), 2);
  now = run_windows(choice, 1, 2, 1.0, 1.9, now + TeamChoice::kPeriod);
  EXPECT_EQ(choice.plan(2, now).threads, 2);
}

TEST_F(TeamChoiceTest, HandsTheRegionsToOneThreadWhileTheTeamLosesThenBackWhenItWins) {
  TeamChoice choice(pressure_ns);
  // a team slowed by cores busy with threads that do not wait for them: one thread from then on, the collision
  // pipeline's too
  std::int64_t now = run_windows(choice, 2, 2, 0.67, 0.6, start(choice));
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, false));
  EXPECT_EQ(choice.threads(4), 1);
  EXPECT_EQ(choice.threads(1), 1);
  // after the first wait: one thread measured, then the team, which loses again; the next wait is twice as long
  now += TeamChoice::kFirstWait;
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));
  now = run_windows(choice, 1, 2, 0.67, 0.6, now);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, true));
  EXPECT_EQ(choice.threads(2), 2);  // (a try of the team takes the collision pipeline's regions too)
  now = run_windows(choice, 1, 2, 0.67, 0.6, now);
  EXPECT_EQ(of(choice.plan(2, now + 2 * TeamChoice::kFirstWait - 1)), std::make_pair(1, false));
  // the waits double up to the longest
  for (int k = 0; k < 8; ++k) now = run_windows(choice, 2, 2, 0.67, 0.6, now + TeamChoice::kLongestWait);
  EXPECT_EQ(of(choice.plan(2, now + TeamChoice::kLongestWait - 1)), std::make_pair(1, false));
  // the other threads gone: the team wins its next try and is kept
  now = run_windows(choice, 2, 2, 1.0, 1.9, now + TeamChoice::kLongestWait);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, false));
  EXPECT_EQ(choice.threads(2), 2);
  // and handed over again only after its next window, with the first wait again
  now = run_windows(choice, 1, 2, 1.0, 0.6, now + TeamChoice::kPeriod);
  EXPECT_EQ(choice.plan(2, now + TeamChoice::kFirstWait - 1).threads, 1);
  EXPECT_EQ(of(choice.plan(2, now + TeamChoice::kFirstWait)), std::make_pair(1, true));
}

TEST_F(TeamChoiceTest, ATeamThatClearlyLosesIsHandedOverAfterOneRegion) {
  TeamChoice choice(pressure_ns);
  int regions = 0;
  std::int64_t now = run_windows(choice, 1, 2, 0.67, 0.3, start(choice), &regions);  // one thread's window
  EXPECT_EQ(regions, TeamChoice::kWindowRegions);
  now = run_windows(choice, 1, 2, 0.67, 0.3, now, &regions);  // below half of one thread's 0.67
  EXPECT_EQ(regions, 1);
  EXPECT_EQ(choice.plan(2, now).threads, 1);
  // a team within half of one thread's rate gets a whole window
  now = run_windows(choice, 2, 2, 0.67, 0.4, now + 2 * TeamChoice::kFirstWait, &regions);
  EXPECT_EQ(regions, 2 * TeamChoice::kWindowRegions);
  EXPECT_EQ(choice.plan(2, now).threads, 1);
}

TEST_F(TeamChoiceTest, NoTryWhileThreadsWaitForACoreUntilTheLongestWait) {
  TeamChoice choice(pressure_ns);
  busy = 1;  // some thread always waits for a core
  std::int64_t now = start(choice);
  // the waits double without a try
  for (std::int64_t wait = TeamChoice::kFirstWait; wait <= TeamChoice::kLongestWait; wait *= 2) {
    EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, false));
    advance(now, wait - 1);
    EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, false));
    advance(now, 1);
  }
  // a try at the longest wait, whatever the pressure: lost, and the next waits are the longest
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));
  now = run_windows(choice, 2, 2, 0.67, 0.3, now);
  advance(now, TeamChoice::kLongestWait - 1);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, false));
  advance(now, 1);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));
  now = run_windows(choice, 2, 2, 0.67, 0.3, now);
  // the pressure below a quarter of the time: the team wins its next try, and after it loses a window it is
  // tried again after the first wait
  busy = 0.2;
  advance(now, TeamChoice::kLongestWait);
  now = run_windows(choice, 2, 2, 1.0, 1.9, now);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, false));
  now = run_windows(choice, 1, 2, 1.0, 0.6, now + TeamChoice::kPeriod);
  advance(now, TeamChoice::kFirstWait);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));
}

TEST_F(TeamChoiceTest, KeepsATeamWithinATenthOfOneThreadsRate) {
  TeamChoice choice(pressure_ns);
  std::int64_t now = run_windows(choice, 2, 2, 0.7, 0.8, start(choice));
  EXPECT_EQ(choice.plan(2, now).threads, 2);
  now = run_windows(choice, 1, 2, 0.7, 0.65, now + TeamChoice::kPeriod);
  EXPECT_EQ(choice.plan(2, now).threads, 2);
  now = run_windows(choice, 1, 2, 0.7, 0.6, now + TeamChoice::kPeriod);
  EXPECT_EQ(choice.plan(2, now).threads, 1);
}

TEST_F(TeamChoiceTest, TriesTheTeamWhereThePressureIsNotTold) {
  TeamChoice choice([]() -> std::int64_t { return -1; });
  std::int64_t now = start(choice);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(1, true));
  now = run_windows(choice, 2, 2, 1.0, 1.9, now);
  EXPECT_EQ(of(choice.plan(2, now)), std::make_pair(2, false));
}

TEST_F(TeamChoiceTest, WithoutAdaptingEveryRegionRunsOnTheThreadsItAsks) {
  TeamChoice choice(pressure_ns);
  run_windows(choice, 2, 2, 0.67, 0.25, start(choice));
  choice.adapt(false);
  EXPECT_EQ(of(choice.plan(3, 0)), std::make_pair(3, false));
  EXPECT_EQ(choice.threads(3), 3);
}

}  // namespace
}  // namespace novaphy
