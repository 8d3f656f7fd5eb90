// The project's conventions have one source each; these tests compare the users' view of
// them against that source and assert the identities the conventions promise.
#include <gtest/gtest.h>

#include <array>

#include <ceres/jet.h>

#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/sky_model.h"

namespace skycal {
namespace {

// The float weights are the float literals (no double rounding on the way).
static_assert(static_cast<float>(kRec709LuminanceWeights[0]) == 0.2126f);
static_assert(static_cast<float>(kRec709LuminanceWeights[1]) == 0.7152f);
static_assert(static_cast<float>(kRec709LuminanceWeights[2]) == 0.0722f);

TEST(Luminance, WeightsAreBt709AndSumToOne) {
  EXPECT_EQ(kRec709LuminanceWeights[0], 0.2126);
  EXPECT_EQ(kRec709LuminanceWeights[1], 0.7152);
  EXPECT_EQ(kRec709LuminanceWeights[2], 0.0722);
  EXPECT_NEAR(Rec709Luminance(1.0, 1.0, 1.0), 1.0, 1e-15);  // white has Y = 1
  EXPECT_NEAR(Rec709Luminance(1.0f, 1.0f, 1.0f), 1.0f, 1e-7f);
  EXPECT_DOUBLE_EQ(Rec709Luminance(std::array<double, 3>{0.5, 2.0, 4.0}), 0.1063 + 1.4304 + 0.2888);
}

TEST(Luminance, FloatAndDoubleEvaluateAsTheWrittenSums) {
  const float r = 0.3f, g = 1.7f, b = 11.0f;
  EXPECT_EQ(Rec709Luminance(r, g, b), 0.2126f * r + 0.7152f * g + 0.0722f * b);
  EXPECT_EQ(Rec709Luminance<double>(r, g, b), 0.2126 * r + 0.7152 * g + 0.0722 * b);
}

TEST(Luminance, JetDerivativesAreTheWeights) {
  using J = ceres::Jet<double, 3>;
  const J y = Rec709Luminance(J(0.5, 0), J(2.0, 1), J(4.0, 2));
  EXPECT_DOUBLE_EQ(y.a, Rec709Luminance(0.5, 2.0, 4.0));
  for (int c = 0; c < 3; ++c) EXPECT_EQ(y.v[c], kRec709LuminanceWeights[c]);
}

// LUT hook the shared model source needs; the tests below call no LUT code.
struct NoLut {
  template <typename S>
  glsl::Vec3<S> texel(int, int, int) const { return glsl::Vec3<S>(S(0.0)); }
};
using ModelD = model::SkyModel<double, NoLut>;

TEST(Constants, PiIsTheModelsPiAndDegreesConvert) {
  EXPECT_EQ(kPi, ModelD::SC_PI);  // the GLSL model's literal
  EXPECT_EQ(kPi, 3.14159265358979323846);
  EXPECT_EQ(DegToRad(180.0), kPi);
  EXPECT_EQ(RadToDeg(kPi), 180.0);
  EXPECT_EQ(DegToRad(90.0), kPi / 2);
  EXPECT_EQ(kRadiansPerDegree, kPi / 180.0);
  EXPECT_NEAR(kRadiansPerDegree * kDegreesPerRadian, 1.0, 1e-16);
  EXPECT_EQ(DegToRad(37.5), 37.5 * kPi / 180.0);  // the inline form the project writes
}

}  // namespace
}  // namespace skycal
