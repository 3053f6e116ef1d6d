#include "engine/solver/route.h"

#include <gtest/gtest.h>

#include <vector>

namespace novaphy {
namespace {

// a route of one unit that records the stages it is asked to run
class RecordingRoute : public StepRoute {
 public:
  std::vector<Stage> ran;
  int unit_count() const override { return 1; }
  int unit_articulations(int, int* out) const override {
    out[0] = 0;
    return 1;
  }
  void begin_step(const StepContext&) override {}
  void end_step(const StepContext&) override {}
  void dynamics(const UnitPass&, const StepContext&, const UnitInputs&) override { ran.push_back(Stage::Dynamics); }
  void rows(const UnitPass&, const StepContext&) override { ran.push_back(Stage::Rows); }
  void integrate(const UnitPass&, const StepContext&) override { ran.push_back(Stage::Integrate); }
  void store(const UnitPass&, const StepContext&) override { ran.push_back(Stage::Store); }
  void solve_mass(int, Scalar*) override {}
  void point_jacobian(int, int, const Vec3*, const Vec3&, Scalar, Scalar*) const override {}
  std::size_t bytes() const override { return 0; }
};

std::vector<Stage> run(Stage first, Stage last, bool timed) {
  RecordingRoute route;
  UnitStageSeconds seconds;
  run_unit(route, {0, first, last}, StepContext{}, UnitInputs{}, timed ? &seconds : nullptr);
  return route.ran;
}

TEST(Route, RunUnitRunsAUnitsStagesInThePhysicsOrderSkippingTheSteps) {
  using S = Stage;
  EXPECT_EQ(run(S::Dynamics, S::Store, false), (std::vector<S>{S::Dynamics, S::Rows, S::Integrate, S::Store}));
  EXPECT_EQ(run(S::Dynamics, S::Rows, true), (std::vector<S>{S::Dynamics, S::Rows}));
  EXPECT_EQ(run(S::Integrate, S::Store, true), (std::vector<S>{S::Integrate, S::Store}));
  EXPECT_EQ(run(S::Store, S::Store, false), (std::vector<S>{S::Store}));
  // the list holds each stage once, in increasing order, and the two step stages between the unit stages
  for (size_t i = 1; i < std::size(kStages); ++i) EXPECT_LT(kStages[i - 1], kStages[i]);
  EXPECT_FALSE(unit_stage(S::Islands));
  EXPECT_FALSE(unit_stage(S::Guard));
}

TEST(Route, UnitsWaitForTheIslandsAndForTheGuardOnlyWhereADivergenceRaises) {
  StepContext step;
  EXPECT_FALSE(step.runs(Stage::Islands));
  step.split = true;
  EXPECT_TRUE(step.runs(Stage::Islands));
  EXPECT_TRUE(step.runs(Stage::Guard));
  for (const DivergencePolicy policy : {DivergencePolicy::Raise, DivergencePolicy::Flag, DivergencePolicy::Reset}) {
    step.settings.on_divergence = policy;
    EXPECT_TRUE(step.waits_for(Stage::Islands));
    EXPECT_EQ(step.waits_for(Stage::Guard), policy == DivergencePolicy::Raise);
  }
}

}  // namespace
}  // namespace novaphy
