// core/latlong_resample.h: identities, the block mean, the mean kept at any factor, the mean
// over positive pixels, bad sizes.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/core/latlong_resample.h"

namespace skycal {
namespace {

std::vector<float> Ramp(int w, int h, int channels) {
  std::vector<float> v(static_cast<size_t>(w) * h * channels);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>((i * 37) % 101) / 7.0f;
  return v;
}

TEST(AreaDownsampleLatLong, TheSameSizeIsTheInput) {
  const auto v = Ramp(10, 5, 3);
  EXPECT_EQ(AreaDownsampleLatLong(v, 10, 5, 3, 10, 5), v);
}

TEST(AreaDownsampleLatLong, AnIntegerFactorIsTheBlockMean) {
  const auto v = Ramp(8, 4, 1);
  const auto d = AreaDownsampleLatLong(v, 8, 4, 1, 4, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      const float want = (v[(2 * y) * 8 + 2 * x] + v[(2 * y) * 8 + 2 * x + 1] + v[(2 * y + 1) * 8 + 2 * x] +
                          v[(2 * y + 1) * 8 + 2 * x + 1]) / 4.0f;
      EXPECT_NEAR(d[y * 4 + x], want, 1e-5) << x << "," << y;
    }
}

// Every input pixel is shared out whole (its overlaps sum to 1), so the mean over the image
// is kept at any factor, per channel; a constant stays constant.
TEST(AreaDownsampleLatLong, AnyFactorKeepsTheMean) {
  const int w = 1000, h = 500;
  const auto v = Ramp(w, h, 3);
  for (auto [ow, oh] : {std::pair{512, 256}, std::pair{333, 111}, std::pair{7, 3}}) {
    const auto d = AreaDownsampleLatLong(v, w, h, 3, ow, oh);
    for (int c = 0; c < 3; ++c) {
      double in = 0.0, out = 0.0;
      for (size_t i = c; i < v.size(); i += 3) in += v[i];
      for (size_t i = c; i < d.size(); i += 3) out += d[i];
      EXPECT_NEAR(out / (static_cast<double>(ow) * oh), in / (static_cast<double>(w) * h), 1e-4) << ow << " channel " << c;
    }
  }
  const std::vector<float> flat(600 * 300, 2.5f);
  for (float x : AreaDownsampleLatLong(flat, 600, 300, 1, 512, 256)) EXPECT_NEAR(x, 2.5f, 1e-6);
}

TEST(AreaDownsampleLatLong, BlocksAndFractionsByHand) {
  std::vector<float> v(8 * 4);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i);
  const auto d = AreaDownsampleLatLong(v, 8, 4, 1, 4, 2);
  ASSERT_EQ(d.size(), 8u);
  EXPECT_FLOAT_EQ(d[0], (0.0f + 1 + 8 + 9) / 4);
  EXPECT_FLOAT_EQ(d[7], (22.0f + 23 + 30 + 31) / 4);
  // A size that is no multiple: output pixel 0 covers columns 0, 1 and 2/3 of column 2, rows 0
  // and 1: (0 + 1 + 2 x 2/3 + 8 + 9 + 10 x 2/3) / (2 x 8/3).
  const auto a = AreaDownsampleLatLong(v, 8, 4, 1, 3, 2);
  ASSERT_EQ(a.size(), 6u);
  EXPECT_NEAR(a[0], 26.0 / (16.0 / 3.0), 1e-5);
  EXPECT_THROW(AreaDownsampleLatLong(v, 8, 4, 1, 16, 8), Error);  // larger: refused
}

// Over the positive pixels only: a zeroed (or negative, or NaN) pixel leaves its block's mean
// to the others; a block of none is 0. Control: the plain mean, darkened by the zero.
TEST(AreaDownsampleLatLong, OfPositiveLeavesBadPixelsOut) {
  std::vector<float> v(8 * 4 * 3, 2.0f);
  for (int c = 0; c < 3; ++c) {
    v[3 * 0 + c] = 0.0f;                            // block (0, 0): one of four zeroed
    v[3 * 1 + c] = 6.0f;                            // ... and one brighter: mean of 6, 2, 2 = 10/3
    for (int p : {2, 3, 10, 11}) v[3 * p + c] = 0.0f;  // block (1, 0): all four zeroed
  }
  v[3 * 12 + 1] = std::numeric_limits<float>::quiet_NaN();  // block (2, 0): one NaN channel
  v[3 * 21 + 2] = -1.0f;                                    // block (2, 1): one negative channel
  const auto d = AreaDownsampleLatLongOfPositive(v, 8, 4, 3, 4, 2);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(d[3 * 0 + c], 10.0f / 3.0f, 1e-5);
    EXPECT_EQ(d[3 * 1 + c], 0.0f);
    EXPECT_NEAR(d[3 * 2 + c], 2.0f, 1e-6);  // the NaN pixel left out
    EXPECT_NEAR(d[3 * (4 + 2) + c], 2.0f, 1e-6);  // the negative pixel left out
    EXPECT_NEAR(d[3 * 3 + c], 2.0f, 1e-6);
  }
  const auto plain = AreaDownsampleLatLong(v, 8, 4, 3, 4, 2);
  EXPECT_NEAR(plain[0], 2.5f, 1e-5);  // (0 + 6 + 2 + 2) / 4
  EXPECT_THROW(AreaDownsampleLatLongOfPositive(v, 8, 4, 3, 9, 2), Error);
}

TEST(AreaDownsampleLatLong, BadSizesAreNamed) {
  const auto v = Ramp(8, 4, 1);
  for (auto [ow, oh] : {std::pair{16, 8}, std::pair{0, 2}, std::pair{4, 0}}) {
    try {
      AreaDownsampleLatLong(v, 8, 4, 1, ow, oh);
      ADD_FAILURE() << ow << "x" << oh;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("8x4 to " + std::to_string(ow) + "x" + std::to_string(oh)), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(AreaDownsampleLatLong(v, 8, 4, 3, 4, 2), Error);  // 32 values are not 8x4x3
}

}  // namespace
}  // namespace skycal
