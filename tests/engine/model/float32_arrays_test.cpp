// A float32 model's State and Control as float32 arrays (State::float32, Control::float32): made with them,
// widened and rounded exactly, and a loop that keeps the state in float32 between steps stepping the same bits as
// one that keeps it in double.
#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "engine/model/error.h"
#include "solver_test_support.h"

namespace novaphy {
namespace {

using solver_test::Scene;

ModelBuilder quadrupeds(Precision precision, int worlds) {
  ModelBuilder robot;
  import_mjcf(robot, NOVAPHY_SCENE_DIR "/quadruped.xml");
  ModelBuilder scene;
  scene.set_precision(precision);
  scene.replicate(robot, worlds);
  return scene;
}

template <typename T>
std::vector<float> rounded(const std::vector<T>& values) {
  return std::vector<float>(values.begin(), values.end());
}

// every value of `values` a float
bool all_floats(const std::vector<Scalar>& values) {
  for (const Scalar v : values)
    if (static_cast<Scalar>(static_cast<float>(v)) != v) return false;
  return true;
}

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Float32Arrays, AFloat32ModelsStateAndControlHoldThemRounded) {
  const Model model = quadrupeds(Precision::Float32, 3).finalize();
  const State state = model.state();
  EXPECT_EQ(state.precision, Precision::Float32);
  EXPECT_EQ(state.float32.joint_q, rounded(state.joint_q));
  EXPECT_EQ(state.float32.body_q, rounded(state.body_q));
  EXPECT_EQ(state.float32.body_qd, rounded(state.body_qd));
  EXPECT_EQ(state.float32.world_reset, state.world_reset);
  const Control control = model.control();
  EXPECT_EQ(control.float32.joint_target_ke, rounded(control.joint_target_ke));
  EXPECT_EQ(control.float32.actuator_ctrl.size(), control.actuator_ctrl.size());

  const Model wide = quadrupeds(Precision::Float64, 3).finalize();
  EXPECT_TRUE(wide.state().float32.joint_q.empty());
  EXPECT_TRUE(wide.control().float32.joint_f.empty());
}

TEST(Float32Arrays, WideningAndRoundingAreExactOnFloats) {
  const Model model = quadrupeds(Precision::Float32, 2).finalize();
  State state = model.state();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2, 2);
  for (float& v : state.float32.joint_qd) v = u(rng);
  state.from_float32();
  EXPECT_EQ(rounded(state.joint_qd), state.float32.joint_qd);
  const std::vector<Scalar> widened = state.joint_qd;
  state.to_float32(1);
  state.from_float32(2);
  EXPECT_EQ(state.joint_qd, widened);
}

// the same worlds stepped twice from the same (float) start under the same (float) commands: once with the
// state kept in double, once widened from float32 before each step and rounded into it after
TEST(Float32Arrays, AStateKeptInFloat32StepsTheSameBits) {
  Scene wide(quadrupeds(Precision::Float32, 5));
  Scene narrow(quadrupeds(Precision::Float32, 5));
  wide.state.to_float32();
  wide.state.from_float32();
  const std::vector<Scalar> start = wide.state.joint_q;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int step = 0; step < 200; ++step) {
    for (size_t k = 0; k < wide.control.actuator_ctrl.size(); ++k)
      wide.control.actuator_ctrl[k] = narrow.control.float32.actuator_ctrl[k] = u(rng);
    wide.run(0.002, 0.002);
    narrow.state.from_float32();
    narrow.control.from_float32();
    narrow.run(0.002, 0.002);
    narrow.state.to_float32();
  }
  for (std::vector<Scalar> State::*field : {&State::joint_q, &State::joint_qd, &State::body_q, &State::body_qd}) {
    EXPECT_TRUE(all_floats(wide.state.*field));
    EXPECT_EQ(narrow.state.*field, wide.state.*field);
  }
  EXPECT_NE(wide.state.joint_q, start);
  EXPECT_EQ(narrow.state.float32.joint_q, rounded(wide.state.joint_q));
  EXPECT_EQ(narrow.state.float32.sensor_data, rounded(wide.state.sensor_data));
}

TEST(Float32Arrays, OtherPrecisionsAndShortArraysAreRefused) {
  const Model model = quadrupeds(Precision::Float32, 2).finalize();
  const Model wide = quadrupeds(Precision::Float64, 2).finalize();
  State state = model.state();
  EXPECT_NE(error_of([&] { state.assign(wide.state()); }).find("assign: the other state is float64, this one float32"),
            std::string::npos);
  Control control = model.control();
  EXPECT_NE(error_of([&] { control.assign(wide.control()); }).find("the other control is float64"), std::string::npos);
  state.float32.joint_qd.pop_back();
  EXPECT_NE(error_of([&] { model.check(state); }).find("state: float32.joint_qd has"), std::string::npos);
}

}  // namespace
}  // namespace novaphy
