// The fit's linear structure (fit/src/linear_sky.h): identities that must hold exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "fit_state.h"
#include "linear_sky.h"
#include "linear_start.h"
#include "pyramid.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
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
OwnSky OwnRender(const testing::ScratchDir& dir, render::ModelVariant variant, double elevation, double overcast,
                 int width = 128) {
  OwnSky s;
  s.truth = testing::RandomPreset(11, variant);
  s.truth.overcast_weight = overcast;
  s.truth.haziness_g = 0.7;
  const std::string path = dir / "own.exr";
  refsky::WriteModelReference(path, s.truth, latlong::DirectionFromElevationAzimuthDeg(elevation, 15.0), width);
  FitOptions o;
  o.variant = variant;
  s.ref = LoadReference(path, o);
  // Start elsewhere: the preset's LUT halved, L_z doubled (the solve must not need the truth).
  render::Preset start = s.truth;
  for (auto* t : {&start.luts.rayleigh, &start.luts.mie, &start.luts.isotropic})
    for (float& v : *t) v *= 0.5f;
  start.overcast_zenith_cd_m2 *= 2.0;
  s.state = FitState::FromPreset(start, variant, 1);
  s.level = BuildLevel(s.ref, width);
  return s;
}

// A tied-rows solution rendered as the fit writes it (the two LUT rows around the sun), at
// the level's size, without the disc or the ground.
ImageRGB RenderTied(const LinearSky& sky, const LinearSkySolution& sol, OwnSky* s) {
  const auto& grid = s->state.preset.luts.grid;
  const double pos = (1.0 - s->ref.sun_dir[1]) / (1.0 - std::cos(grid.theta_max_deg * M_PI / 180.0)) * (grid.n_theta - 1);
  s->state.tied_rows = {static_cast<int>(std::floor(pos)), static_cast<int>(std::floor(pos)) + 1};
  sky.Apply(sol, &s->state);
  s->state.g = sol.g;
  render::RenderRequest req;
  req.sun_dir = s->ref.sun_dir;
  req.width = s->level.width;
  req.height = s->level.height;
  req.sun_disc = false;
  req.ground = render::GroundMode::kZero;
  return render::CreateRenderer(render::Backend::kCpu)->Render(s->state.ToPreset(), req);
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

// Stripes along the horizon where no pixel sees it: per image row at 0.5-10 deg elevation,
// the mean over the columns within 60 deg of azimuth of the sun of ln(Y / Y_truth); the RMS
// of its second difference from row to row.
double HorizonBanding(const ImageRGB& image, const ImageRGB& truth, double sun_azimuth_deg) {
  std::vector<double> profile;
  for (int y = 0; y < image.height; ++y) {
    const double elevation = latlong::Latitude(y, image.height) * 180.0 / M_PI;
    if (elevation < 0.5 || elevation > 10.0) continue;
    double sum = 0.0;
    int n = 0;
    for (int x = 0; x < image.width; ++x) {
      const double az = latlong::AzimuthDeg(latlong::PixelDirection(x, y, image.width, image.height));
      if (std::abs(std::remainder(az - sun_azimuth_deg, 360.0)) > 60.0) continue;
      auto lum = [&](const ImageRGB& im) {
        return Rec709Luminance<double>(im.at(x, y, 0), im.at(x, y, 1), im.at(x, y, 2));
      };
      sum += std::log(lum(image) / lum(truth));
      ++n;
    }
    profile.push_back(sum / n);
  }
  double sq = 0.0;
  for (size_t i = 1; i + 1 < profile.size(); ++i) sq += std::pow(profile[i - 1] - 2.0 * profile[i] + profile[i + 1], 2);
  return std::sqrt(sq / static_cast<double>(profile.size() - 2));
}

// The horizon masked below 10 deg but for 60 deg of azimuth opposite the sun (azimuth 15),
// whose image rows there are alternately x1.25 and x0.8 (a haze line, a far shore): the
// columns they read are seen only there. Per pixel: 0 masked, the stripe's factor, or 1.
float MaskedHorizonFactor(int x, int y, int width, int height) {
  const auto d = latlong::PixelDirection(x, y, width, height);
  if (latlong::ElevationDeg(d) > 10.0) return 1.0f;
  if (std::abs(std::remainder(latlong::AzimuthDeg(d) - 195.0, 360.0)) > 30.0) return 0.0f;
  return y % 2 ? 1.25f : 0.8f;
}

// The masked, striped horizon on a level. Returns the truth's relative error against the
// striped pixels (what a fit that ignored the stripes would leave).
double StripeAMaskedHorizon(FitLevel* level) {
  double stripes_sq = 0.0, total_weight = 0.0;
  for (int y = 0; y < level->height; ++y)
    for (int x = 0; x < level->width; ++x) {
      const size_t i = static_cast<size_t>(y) * level->width + x;
      const float f = MaskedHorizonFactor(x, y, level->width, level->height);
      if (f == 0.0f) level->weight[i] = 0.0;
      if (f != 0.0f && f != 1.0f) {
        for (int c = 0; c < 3; ++c) level->radiance[3 * i + c] *= f;
        stripes_sq += 3.0 * level->weight[i] * std::pow(1.0 / f - 1.0, 2);
      }
      total_weight += 3.0 * level->weight[i];
    }
  return std::sqrt(stripes_sq / total_weight);
}

ImageRGB RenderAt(const render::Preset& preset, const Reference& ref, int width, int height) {
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = width;
  req.height = height;
  req.sun_disc = false;
  req.ground = render::GroundMode::kZero;
  return render::CreateRenderer(render::Backend::kCpu)->Render(preset, req);
}

// The fit's steps: the relative solve, then Gauss-Newton on the log error.
LinearSkySolution SolveAsTheFit(const LinearSky& sky, const std::vector<double>& exposures) {
  LinearSkySolution sol = sky.Solve(0.7, exposures, {});
  for (int step = 0; step < 6; ++step) sol = sky.Solve(0.7, exposures, {}, &sol);
  return sol;
}

TEST(LinearSky, TheUnseenProfileDrawsAMaskedHorizonSmoothlyAndLeavesASkySeenAllRoundAlone) {
  testing::ScratchDir dir("linear-unseen");
  OwnSky s = OwnRender(dir, render::ModelVariant::kFfxvIso, 27.0, 0.0, 256);
  LinearSkyOptions off, on;
  off.unseen_profile = 0.0;
  on.unseen_profile = 1e-4;  // FitOptions' default
  {
    // Seen all round: no term, the same solution to the bit.
    const LinearSky a(s.state, {&s.level}, {s.ref}, off), b(s.state, {&s.level}, {s.ref}, on);
    EXPECT_EQ(b.partly_seen_columns(), 0);
    EXPECT_EQ(b.unseen_profile_terms(), 0);
    EXPECT_EQ(a.Solve(0.7, {1.0}, {}).values, b.Solve(0.7, {1.0}, {}).values);
  }
  const double stripes_rms = StripeAMaskedHorizon(&s.level);
  const ImageRGB truth = RenderAt(s.truth, s.ref, s.level.width, s.level.height);
  double banding[2], rel_rmse[2];
  for (int k = 0; k < 2; ++k) {
    const LinearSky sky(s.state, {&s.level}, {s.ref}, k ? on : off);
    if (k) {
      EXPECT_GT(sky.partly_seen_columns(), 3);
      EXPECT_GT(sky.unseen_profile_terms(), 100);
    }
    const LinearSkySolution sol = SolveAsTheFit(sky, {1.0});
    rel_rmse[k] = sol.rel_rmse;
    banding[k] = HorizonBanding(RenderTied(sky, sol, &s), truth, 15.0);
  }
  // The control: without the prior the game draws the sector's stripes on the sun's side,
  // and the pixels are fitted exactly (the columns follow the rows one by one).
  EXPECT_GT(banding[0], 0.5) << "off";
  EXPECT_LT(rel_rmse[0], 1e-3) << "off";
  // With it the stripes there are a fraction (3 tables x 3 channels per column cannot draw
  // the stripes opposite the sun and none beside it: Rayleigh's phase is symmetric).
  EXPECT_LT(banding[1], 0.3 * banding[0]) << "on: " << banding[1] << ", off: " << banding[0];
  // What the pixels see is still mostly fitted: the error is a fraction of the stripes'.
  EXPECT_LT(rel_rmse[1], 0.3 * stripes_rms) << "on: " << rel_rmse[1] << ", the stripes " << stripes_rms;
}

// A day (free rows: every LUT row an unknown, the references' suns 27 and 35 deg) from one
// camera, the same masked and striped horizon in both frames: the joint steps keep what
// each reference's prior drew.
TEST(LinearSky, TheUnseenProfileHoldsForADayOfFreeRows) {
  testing::ScratchDir dir("linear-unseen-day");
  OwnSky a = OwnRender(dir, render::ModelVariant::kFfxvIso, 27.0, 0.0, 256);
  testing::ScratchDir dir2("linear-unseen-day2");
  OwnSky b = OwnRender(dir2, render::ModelVariant::kFfxvIso, 35.0, 0.0, 256);
  StripeAMaskedHorizon(&a.level);
  StripeAMaskedHorizon(&b.level);
  const std::vector<Reference> refs = {a.ref, b.ref};
  FitState state = FitState::FromPreset(render::Preset(a.state.preset), render::ModelVariant::kFfxvIso, 2);
  const ImageRGB truth = RenderAt(a.truth, a.ref, a.level.width, a.level.height);
  double banding[2];
  for (int k = 0; k < 2; ++k) {
    LinearSkyOptions lo;
    lo.unknowns = LinearUnknowns::kFreeRows;
    lo.row_fitted.assign(state.preset.luts.grid.n_theta, true);
    lo.unseen_profile = k ? 1e-4 : 0.0;
    const LinearSky day(state, {&a.level, &b.level}, refs, lo);
    if (k) {
      EXPECT_GT(day.unseen_profile_terms(), 200);
    }
    const LinearSkySolution sol = SolveAsTheFit(day, {1.0, 1.0});
    FitState fitted = state;
    day.Apply(sol, &fitted);
    fitted.g = sol.g;
    banding[k] = HorizonBanding(RenderAt(fitted.ToPreset(), a.ref, a.level.width, a.level.height), truth, 15.0);
  }
  EXPECT_GT(banding[0], 0.5) << "off";
  EXPECT_LT(banding[1], 0.3 * banding[0]) << "on: " << banding[1] << ", off: " << banding[0];
}

// The Ceres polish (it runs with a probe, or --polish) keeps what the linear start drew where
// no pixel looks: without the prior in the polish, the polish put the stripes back.
TEST(LinearSky, ThePolishKeepsTheUnseenProfile) {
  testing::ScratchDir dir("linear-unseen-polish");
  OwnSky s = OwnRender(dir, render::ModelVariant::kFfxvIso, 27.0, 0.0, 256);
  const ImageRGB truth = RenderAt(s.truth, s.ref, s.level.width, s.level.height);
  // The same mask and stripes as above, on the reference itself.
  Reference striped = s.ref;
  for (int y = 0; y < striped.radiance.height; ++y)
    for (int x = 0; x < striped.radiance.width; ++x) {
      const float f = MaskedHorizonFactor(x, y, striped.radiance.width, striped.radiance.height);
      const size_t i = static_cast<size_t>(y) * striped.radiance.width + x;
      if (f == 0.0f && striped.pixel_class[i] == PixelClass::kSky) striped.pixel_class[i] = PixelClass::kUserMasked;
      if (f != 0.0f)
        for (int c = 0; c < 3; ++c) striped.radiance.at(x, y, c) *= f;
    }
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  double banding[2];
  for (int k = 0; k < 2; ++k) {
    FitOptions o;
    o.variant = render::ModelVariant::kFfxvIso;
    o.polish = true;
    o.verbose = false;
    o.unseen_profile = k ? 1e-4 : 0.0;
    const FitResult r = FitSky({striped}, s.state.preset, o, *cpu);
    ASSERT_GT(r.iterations, 0) << "the polish ran";
    banding[k] = HorizonBanding(RenderAt(r.preset, s.ref, s.level.width, s.level.height), truth, 15.0);
  }
  EXPECT_GT(banding[0], 0.5) << "off";
  EXPECT_LT(banding[1], 0.3 * banding[0]) << "on: " << banding[1] << ", off: " << banding[0];
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
