// The tiled transposes between worlds' rows of doubles and lanes against their twins, which move
// one number at a time: every row length to a few tiles past one, rows at odd offsets in one buffer
// (unaligned loads and stores), every lane written or not, bit for bit (NaN and values that round
// in float included); nothing outside a written row's numbers touched. Likewise one vector of doubles
// to lanes and back (a block's kept limit impulses): each lane converted on its own, the lanes not
// written keeping their doubles' bits
#include "kernels/lane_transpose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace novaphy {
namespace {

template <typename T>
void expect_transposes_equal_their_twins() {
  constexpr int W = kLanes<T>;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int count = 0; count <= 5 * lane_detail::kChunk + 3; ++count) {
    const int stride = count + 3;  // rows at offsets 1, 1 + stride, ...: unaligned
    std::vector<double> source(1 + W * stride + 8);
    for (double& x : source) x = u(rng) + 1e-9 * u(rng);
    source[1] = std::numeric_limits<double>::quiet_NaN();
    if (count > 1) source[1 + stride + 1] = -std::numeric_limits<double>::infinity();
    const double* in_rows[W];
    for (int l = 0; l < W; ++l) in_rows[l] = source.data() + 1 + l * stride;
    std::vector<Lanes<T>> lanes(count + 1), expected(count + 1);
    lanes_from_rows<T>(in_rows, count, lanes.data());
    lanes_from_rows_reference<T>(in_rows, count, expected.data());
    ASSERT_EQ(std::memcmp(lanes.data(), expected.data(), count * sizeof(Lanes<T>)), 0) << count << " numbers in";

    IntLanes<T> written{};
    for (int l = 0; l < W; ++l) written[l] = rng() % 3 == 0 ? 0 : -1;
    std::vector<double> out(source.size(), -1.0), out_expected(source.size(), -1.0);
    double* out_rows[W];
    double* expected_rows[W];
    for (int l = 0; l < W; ++l) {
      out_rows[l] = out.data() + 1 + l * stride;
      expected_rows[l] = out_expected.data() + 1 + l * stride;
    }
    rows_from_lanes<T>(lanes.data(), count, written, out_rows);
    rows_from_lanes_reference<T>(lanes.data(), count, written, expected_rows);
    ASSERT_EQ(std::memcmp(out.data(), out_expected.data(), out.size() * sizeof(double)), 0) << count << " numbers out";
  }
}

template <typename T>
void expect_one_vector_each_lane() {
  constexpr int W = kLanes<T>;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> buffer(W + 2);  // the vector at offset 1: unaligned
    for (double& x : buffer) x = u(rng) + 1e-9 * u(rng);
    buffer[1 + trial % W] = trial % 2 ? std::numeric_limits<double>::quiet_NaN() : -HUGE_VAL;
    const Lanes<T> x = lanes_from_doubles<T>(buffer.data() + 1);
    for (int l = 0; l < W; ++l) {
      const T expected = static_cast<T>(buffer[1 + l]);
      ASSERT_EQ(std::memcmp(&x[l], &expected, sizeof(T)), 0) << "lane " << l << " in";
    }
    Lanes<T> y;
    IntLanes<T> written{};
    for (int l = 0; l < W; ++l) {
      y[l] = static_cast<T>(u(rng));
      written[l] = rng() % 3 == 0 ? 0 : -1;
    }
    std::vector<double> expected = buffer;
    for (int l = 0; l < W; ++l)
      if (written[l]) expected[1 + l] = y[l];
    doubles_from_lanes<T>(y, written, buffer.data() + 1);
    ASSERT_EQ(std::memcmp(buffer.data(), expected.data(), buffer.size() * sizeof(double)), 0) << "trial " << trial;
  }
}

TEST(LaneTranspose, Float64TilesEqualTheirTwinsBitForBit) { expect_transposes_equal_their_twins<double>(); }
TEST(LaneTranspose, Float32TilesEqualTheirTwinsBitForBit) { expect_transposes_equal_their_twins<float>(); }
TEST(LaneTranspose, OneVectorOfDoublesIsEachLaneInFloat64) { expect_one_vector_each_lane<double>(); }
TEST(LaneTranspose, OneVectorOfDoublesIsEachLaneInFloat32) { expect_one_vector_each_lane<float>(); }

}  // namespace
}  // namespace novaphy
