// The project's conventions have one source each; these tests compare the users' view of
// them against that source and assert the identities the conventions promise.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <ceres/jet.h>

#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/preset.h"
#include "skycal/render/sky_model.h"
#include "skycal/render/sky_params.h"

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

TEST(LatLong, CoreIsTheModelsMapping) {
  const NoLut lut;
  ModelD m(lut);
  for (int h : {2, 3, 26, 64, 129, 297, 1024}) {
    for (int y = 0; y < h; ++y) EXPECT_EQ(latlong::Latitude(y, h), m.latlong_latitude(y, h)) << y << " of " << h;
    const int w = 2 * h - 1;
    for (int x = 0; x < w; ++x) EXPECT_EQ(latlong::Longitude(x, w), m.latlong_longitude(x, w)) << x << " of " << w;
  }
  const auto d = latlong::Direction(0.3, -2.1);
  const auto v = m.latlong_direction_from_trig(std::sin(0.3), std::cos(0.3), std::sin(-2.1), std::cos(-2.1));
  EXPECT_EQ(d[0], v.x);
  EXPECT_EQ(d[1], v.y);
  EXPECT_EQ(d[2], v.z);
  // The convention's fixed points: top row +pi/2, middle row and column 0, column 0 +pi.
  EXPECT_NEAR(latlong::Latitude(0, 129), kPi / 2, 1e-15);
  EXPECT_EQ(latlong::Latitude(64, 129), 0.0);
  EXPECT_EQ(latlong::Longitude(128, 257), 0.0);
  EXPECT_NEAR(latlong::Longitude(0, 257), kPi, 1e-15);
}

TEST(LatLong, PixelDirectionPixelRoundTrip) {
  for (const auto& [w, h] : {std::pair{257, 129}, std::pair{512, 256}, std::pair{1001, 297}}) {
    double worst = 0.0;
    for (int y = 1; y < h - 1; ++y) {  // the poles have no longitude
      for (int x = 1; x < w - 1; ++x) {  // the seam columns share one direction
        const auto p = latlong::PixelPosition(latlong::PixelDirection(x, y, w, h), w, h);
        worst = std::max({worst, std::abs(p[0] - x), std::abs(p[1] - y)});
      }
    }
    EXPECT_LT(worst, 1e-12) << w << "x" << h;
    for (int y = 0; y < h; ++y) EXPECT_NEAR(latlong::RowOfLatitude(latlong::Latitude(y, h), h), y, 1e-12);
    for (int x = 0; x < w; ++x) EXPECT_NEAR(latlong::ColumnOfLongitude(latlong::Longitude(x, w), w), x, 1e-12);
  }
}

TEST(LutGrid, HostMappingIsTheModelsAndInvertsAtTheNodes) {
  render::LutGrid g;
  g.n_theta = 37;
  g.n_gamma = 64;
  g.theta_max_deg = 108.0;
  const NoLut lut;
  ModelD m(lut);
  ModelD::SkyParams p{};
  p.lut_one_minus_cos_theta_max = render::LutOneMinusCosThetaMax(g);
  p.lut_n_theta = g.n_theta;
  p.lut_n_gamma = g.n_gamma;
  EXPECT_EQ(render::LutOneMinusCosThetaMax(g), 1.0 - std::cos(108.0 * kPi / 180.0));
  for (int i = 0; i <= 400; ++i) {
    const double sun_height = 1.0 - i / 200.0;  // 1 .. -1, past theta_max: clamped
    const auto lr = m.lut_row(sun_height, p);
    EXPECT_EQ(render::LutRowPosition(g, sun_height), lr.row0 + lr.frow) << sun_height;
  }
  for (int row = 0; row < g.n_theta; ++row) {
    EXPECT_NEAR(render::LutRowPosition(g, render::LutRowSunHeight(g, row)), row, 1e-12);
    EXPECT_NEAR(std::cos(render::LutRowSunZenithRad(g, row)), render::LutRowSunHeight(g, row), 1e-15);
  }
  EXPECT_EQ(render::LutRowSunHeight(g, 0), 1.0);
  EXPECT_NEAR(render::LutRowSunZenithRad(g, g.n_theta - 1), 108.0 * kPi / 180.0, 1e-12);
  for (int col = 0; col < g.n_gamma; ++col) {
    const auto lc = m.lut_col(render::LutColumnViewHeight(g, col), p);
    EXPECT_NEAR(lc.col0 + lc.fcol, col, 1e-12);
    EXPECT_NEAR(std::sin(render::LutColumnElevationRad(g, col)), render::LutColumnViewHeight(g, col), 1e-15);
  }
}

TEST(SkyParams, FromPresetCarriesEveryPresetField) {
  render::Preset preset;
  preset.variant = render::ModelVariant::kFfxvIso;
  preset.haziness_g = 0.83;
  preset.overcast_weight = 0.25;
  preset.overcast_zenith_cd_m2 = 3100.0;
  preset.sun_angular_radius_deg = 0.2666;
  preset.sun_limb_darkening = 0.6;
  preset.luts.grid.n_theta = 41;
  preset.luts.grid.n_gamma = 33;
  preset.luts.grid.theta_max_deg = 100.0;
  const auto p = render::SkyParamsFromPreset<ModelD::SkyParams>(preset);
  EXPECT_EQ(p.haziness_g, 0.83);
  EXPECT_EQ(p.isotropic_weight, 1.0);
  EXPECT_EQ(p.overcast_weight, 0.25);
  EXPECT_EQ(p.overcast_zenith, 3100.0);
  EXPECT_EQ(p.sun_radius, 0.2666 * kPi / 180.0);
  // 1 - cos R by its series (1 - std::cos(R) itself cancels to ~1e-11 relative at R = 0.27 deg).
  const double r2 = p.sun_radius * p.sun_radius;
  EXPECT_NEAR(p.sun_one_minus_cos_radius, r2 / 2.0 - r2 * r2 / 24.0 + r2 * r2 * r2 / 720.0, 1e-14 * r2);
  EXPECT_EQ(p.sun_limb_u, 0.6);
  EXPECT_EQ(p.lut_one_minus_cos_theta_max, render::LutOneMinusCosThetaMax(preset.luts.grid));
  EXPECT_EQ(p.lut_n_theta, 41);
  EXPECT_EQ(p.lut_n_gamma, 33);
  EXPECT_EQ(p.sun_dir.y, 0.0);  // the request's, left zero
  EXPECT_EQ(p.sun_centre_radiance.x, 0.0);
  EXPECT_EQ(p.ground_radiance.z, 0.0);
  preset.variant = render::ModelVariant::kFfxv;
  // Any scalar of the model: Jets carry the same values.
  using J = ceres::Jet<double, 2>;
  const auto pj = render::SkyParamsFromPreset<model::SkyModel<J, NoLut>::SkyParams>(preset);
  EXPECT_EQ(pj.isotropic_weight.a, 0.0);
  EXPECT_EQ(pj.haziness_g.a, 0.83);
  EXPECT_EQ(pj.lut_one_minus_cos_theta_max.a, p.lut_one_minus_cos_theta_max);
}

}  // namespace
}  // namespace skycal
