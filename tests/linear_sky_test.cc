// The fit's linear structure (fit/src/linear_sky.h): identities that must hold exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "fit_state.h"
#include "linear_sky.h"
#include "linear_start.h"
#include "pyramid.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/refsky/reference_skies.h"
#include "skycal/render/renderer.h"
#include "test_presets.h"
#include "test_util.h"

namespace skycal::fit {
namespace {

struct OwnSky {
  render::Preset truth;
  Reference ref;
  FitState state;
  FitLevel level;
};

// A random preset's own render: the linear structure must reproduce it exactly.
OwnSky OwnRender(const testing::ScratchDir& dir, render::ModelVariant variant, double elevation, double overcast) {
  OwnSky s;
  s.truth = testing::RandomPreset(11, variant);
  s.truth.overcast_weight = overcast;
  s.truth.haziness_g = 0.7;
  const std::string path = dir / "own.exr";
  refsky::WriteModelReference(path, s.truth, latlong::DirectionFromElevationAzimuthDeg(elevation, 15.0), 128);
  FitOptions o;
  o.variant = variant;
  s.ref = LoadReference(path, o);
  // Start elsewhere: the preset's LUT halved, L_z doubled (the solve must not need the truth).
  render::Preset start = s.truth;
  for (auto* t : {&start.luts.rayleigh, &start.luts.mie, &start.luts.isotropic})
    for (float& v : *t) v *= 0.5f;
  start.overcast_zenith_cd_m2 *= 2.0;
  s.state = FitState::FromPreset(start, variant, 1);
  s.level = BuildLevel(s.ref, 128);
  return s;
}

TEST(LinearSky, SolvesItsOwnRenderExactlyAndTheRendererAgrees) {
  testing::ScratchDir dir("linear-own");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  for (auto variant : {render::ModelVariant::kFfxv, render::ModelVariant::kFfxvIso}) {
    for (double overcast : {0.0, 0.3}) {
      SCOPED_TRACE(std::string(render::ToString(variant)) + " overcast " + std::to_string(overcast));
      OwnSky s = OwnRender(dir, variant, 27.0, overcast);
      LinearSkyOptions lo;
      lo.fit_overcast = overcast > 0.0;
      lo.damping = 0.0;
      const LinearSky sky(s.state, {&s.level}, {s.ref}, lo);
      const LinearSkySolution sol = sky.Solve(0.7, {1.0}, {});
      // Float EXR storage of the reference: ~6e-8 relative.
      EXPECT_LT(sol.rel_rmse, 1e-6);
      // ffxv-iso: L_z is not separable (the overcast shape depends on elevation only, which
      // the isotropic table's columns represent exactly); ffxv: it is.
      if (overcast > 0.0 && variant == render::ModelVariant::kFfxv) {
        EXPECT_NEAR(sol.overcast_zenith / s.truth.overcast_zenith_cd_m2, 1.0, 1e-4);
      }
      // The renderer draws what the structure predicted (float LUT: ~1e-7). Tied rows:
      // the two LUT rows around the sun, as FitSky sets them.
      const auto& grid = s.state.preset.luts.grid;
      const double pos = (1.0 - s.ref.sun_dir[1]) / (1.0 - std::cos(grid.theta_max_deg * M_PI / 180.0)) * (grid.n_theta - 1);
      s.state.tied_rows = {static_cast<int>(std::floor(pos)), static_cast<int>(std::floor(pos)) + 1};
      sky.Apply(sol, &s.state);
      s.state.g = 0.7;
      render::RenderRequest req;
      req.sun_dir = s.ref.sun_dir;
      req.width = 128;
      req.height = 64;
      req.sun_disc = false;
      req.ground = render::GroundMode::kZero;
      const ImageRGB img = cpu->Render(s.state.ToPreset(), req);
      EXPECT_LT(sky.MaxRelativeDifference(sol, {1.0}, {img}), 1e-6);
    }
  }
}

TEST(LinearSky, GaussNewtonOfTheLogErrorIsAFixedPointAtItsOptimum) {
  // Reference = own render x a smooth 10% ripple: the log and relative optima differ.
  testing::ScratchDir dir("linear-gn");
  OwnSky s = OwnRender(dir, render::ModelVariant::kFfxvIso, 40.0, 0.0);
  for (int y = 0; y < s.level.height; ++y)
    for (int x = 0; x < s.level.width; ++x)
      for (int c = 0; c < 3; ++c)
        s.level.radiance[3 * (static_cast<size_t>(y) * s.level.width + x) + c] *=
            static_cast<float>(1.0 + 0.1 * std::sin(0.2 * x + c) * std::cos(0.3 * y));
  const LinearSky sky(s.state, {&s.level}, {s.ref}, LinearSkyOptions{});
  LinearSkySolution sol = sky.Solve(0.7, {1.0}, {});
  const std::vector<double> ones(sky.num_samples(), 1.0);
  double previous = sky.RobustLogCost(sol, {1.0}, RobustLoss::kNone, ones);
  const double relative_optimum_log_cost = previous;
  for (int k = 0; k < 8; ++k) {
    sol = sky.Solve(0.7, {1.0}, {}, &sol);
    const double cost = sky.RobustLogCost(sol, {1.0}, RobustLoss::kNone, ones);
    EXPECT_LE(cost, previous * (1.0 + 1e-9)) << "step " << k;  // Gauss-Newton descends here
    previous = cost;
  }
  EXPECT_LT(previous, relative_optimum_log_cost);  // the log optimum is not the relative one
  // Gauss-Newton converges linearly here (10% residuals, not zero): after 8 steps one more
  // changes no model value by 1e-6 (weakly seen LUT entries may still creep; the image,
  // which is what the objective sees, does not).
  const LinearSkySolution again = sky.Solve(0.7, {1.0}, {}, &sol);
  const std::vector<double> before = sky.ModelValues(sol, {1.0}), after = sky.ModelValues(again, {1.0});
  double worst = 0.0;
  for (size_t i = 0; i < before.size(); ++i) worst = std::max(worst, std::abs(after[i] / before[i] - 1.0));
  EXPECT_LT(worst, 1e-6);
}

TEST(LinearSky, RobustScalesWidenOnlyWhereTheMisfitIsCoherent) {
  // Log residuals: +-1% everywhere, +-20% within 6 deg of the sun, and 3% of the pixels
  // elsewhere at +1.1 (clouds): the sun's ring widens to 2.385 x 1.4826 x 0.2, the other
  // rings stay at the floor (their median ignores the clouds).
  testing::ScratchDir dir("linear-rings");
  OwnSky s = OwnRender(dir, render::ModelVariant::kFfxv, 30.0, 0.0);
  const LinearSky sky(s.state, {&s.level}, {s.ref}, LinearSkyOptions{});
  std::vector<double> e(sky.num_samples());
  for (size_t i = 0; i < e.size(); ++i) {
    const double sign = (i % 2) ? 1.0 : -1.0;
    e[i] = sky.sun_angles_deg()[i] < 6.0 ? 0.2 * sign : (i % 33 == 0 ? 1.1 : 0.01 * sign);
  }
  double sigma = 0.0;
  const RingLossScales r = EstimateRingScales(sky, e, 0.05, &sigma);
  EXPECT_NEAR(sigma, 1.4826 * 0.01, 1e-9);
  EXPECT_NEAR(r.global, 0.05, 1e-12);
  EXPECT_NEAR(r.ring[0], 2.385 * 1.4826 * 0.2, 1e-9);
  for (int k = 1; k < RingLossScales::kRings; ++k) EXPECT_NEAR(r.ring[k], 0.05, 1e-12) << "ring " << k;
  EXPECT_EQ(r.At(3.0), r.ring[0]);
  EXPECT_EQ(r.At(179.0), r.ring[RingLossScales::kRings - 1]);
  EXPECT_NEAR(WeightedMedianAbs({-3.0, 1.0, 2.0}, {1.0, 1.0, 1.0}), 2.0, 0.0);
  EXPECT_NEAR(WeightedMedianAbs({-3.0, 1.0, 2.0}, {10.0, 1.0, 1.0}), 3.0, 0.0);
}

TEST(LinearSky, RefusesLevelsOfDifferentSizesBeforeReadingThemAndNamesBothFiles) {
  // A 128x64 level beside a 64x32 one: the sizes are checked before any pixel is read (the
  // total weight used to be summed with the first level's size over every level), and the
  // message names each reference's file and level size.
  testing::ScratchDir dir("linear-sizes");
  OwnSky s = OwnRender(dir, render::ModelVariant::kFfxv, 30.0, 0.0);
  Reference small = s.ref;
  small.path = "/data/sky-small.exr";
  const FitLevel small_level = BuildLevel(small, 64);
  ASSERT_EQ(small_level.width, 64);
  ASSERT_EQ(small_level.height, 32);
  LinearSkyOptions lo;
  lo.unknowns = LinearUnknowns::kFreeRows;
  lo.row_fitted.assign(s.state.preset.luts.grid.n_theta, true);
  std::string message;
  try {
    const LinearSky sky(s.state, {&s.level, &small_level}, {s.ref, small}, lo);
  } catch (const Error& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("level sizes differ"), std::string::npos) << message;
  EXPECT_NE(message.find("'/data/sky-small.exr' gives a 64x32 level"), std::string::npos) << message;
  EXPECT_NE(message.find("'" + s.ref.path + "' a 128x64 one"), std::string::npos) << message;
  // One level per reference.
  message.clear();
  try {
    const LinearSky sky(s.state, {&s.level}, {s.ref, small}, lo);
  } catch (const Error& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("1 levels for 2 references"), std::string::npos) << message;
}

}  // namespace
}  // namespace skycal::fit
