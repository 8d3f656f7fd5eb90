// skysun::FitSunFromSky: the sun placed from the sky with its disc masked out.
#include "skycal/skysun/sky_sun.h"
#include "skycal/skysun/find_sun.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "skycal/capture/sun_detect.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/refsky/cie_sky.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::skysun {
namespace {

double AngleDeg(const latlong::Vec3d& a, const latlong::Vec3d& b) {
  const double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / M_PI;
}

const refsky::CieSkyType& Type(int t) {
  static const std::vector<refsky::CieSkyType> types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  return types.at(t - 1);
}

// A CIE sky of `type` (1000 x L/Lz, ln noise of sigma `noise`), ground 0.1 below the horizon.
ImageRGB RenderCie(int type, const latlong::Vec3d& sun, double noise, int w = 512, int h = 256) {
  ImageRGB img(w, h);
  std::mt19937 rng(1234);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto v = latlong::PixelDirection(x, y, w, h);
      const double l = v[1] > 0 ? 1000.0 * refsky::CieRelativeLuminance(Type(type), v, sun) * std::exp(noise * n01(rng)) : 0.1;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(l);
    }
  return img;
}

// Sky: above the horizon and more than `disc_deg` from the sun.
std::vector<float> MaskDisc(int w, int h, const latlong::Vec3d& sun, double disc_deg, std::vector<float> mask = {}) {
  if (mask.empty()) mask.assign(static_cast<size_t>(w) * h, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto v = latlong::PixelDirection(x, y, w, h);
      if (v[1] <= 0.0 || AngleDeg(v, sun) < disc_deg) mask[static_cast<size_t>(y) * w + x] = 0.0f;
    }
  return mask;
}

struct SynthCase {
  int type;
  double elevation_deg, azimuth_deg;
};

// Known suns, disc (15 deg) masked, 2% ln noise: the estimate lands within 2 deg (the coarse
// grid is 5 deg, the final 0.25 deg; the noise is independent per pixel and averages out in
// the 3-degree cells) and its uncertainty covers the error.
TEST(SkySun, SyntheticCieSkiesRecoverTheSun) {
  const SynthCase cases[] = {{12, 57.3, 31.7}, {12, 28.6, -101.2}, {13, 11.4, 168.9}, {7, 44.1, 82.6}, {15, 2.3, -17.4}, {11, -4.0, 61.3}};
  for (const auto& sc : cases) {
    const auto sun = latlong::DirectionFromElevationAzimuthDeg(sc.elevation_deg, sc.azimuth_deg);
    const ImageRGB img = RenderCie(sc.type, sun, 0.02);
    const auto t0 = std::chrono::steady_clock::now();
    const SkySunEstimate e = FitSunFromSky(img, MaskDisc(img.width, img.height, sun, 15.0), SkySunOptions{});
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double err = AngleDeg(e.direction, sun);
    std::printf("synthetic type %d el %g az %g: error %.3f deg, uncertainty %.3f deg, type %d, log RMSE %.4f, %.3f s\n",
                sc.type, sc.elevation_deg, sc.azimuth_deg, err, e.uncertainty_deg, e.sky_type, e.log_rmse, secs);
    EXPECT_LT(err, 2.0) << "type " << sc.type << " el " << sc.elevation_deg;
    EXPECT_LE(err, e.uncertainty_deg) << "type " << sc.type << " el " << sc.elevation_deg;
    EXPECT_LT(e.uncertainty_deg, 10.0);
    // The truth itself fits within the tolerance of the best (SkySunOptions defaults).
    const double at_truth = SkyFitCostAt(img, MaskDisc(img.width, img.height, sun, 15.0), SkySunOptions{}, sun);
    EXPECT_LE(at_truth, e.log_rmse * 1.05 + 0.01);
  }
}

// Not the CIE model: the game's sky model (render/, the bundled clear preset, CPU reference,
// no disc) with known suns; the disc region masked as for a photo. Neither model family
// contains this sky, and what is asserted is what it measured plus a margin:
//   35.3 deg: error 6.2 deg, inside its uncertainty 16.8 deg -> error < 9, covered;
//   6.7 deg: azimuth within 0.1 deg, but the best elevation runs to the search's floor
//     (the model's horizon glow is not the CIE indicatrix's) -> azimuth within 2 deg, the
//     bound flagged and EstimateSunFromSky refuses;
//   -3.8 deg: the model's sky below the horizon is symmetric between the sun and the
//     anti-sun -> uncertainty > 90 deg and refused.
ImageRGB RenderGameSky(const latlong::Vec3d& sun) {
  static const render::Preset preset =
      render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = 512;
  req.height = 256;
  req.sun_disc = false;
  return cpu->Render(preset, req);
}

SkySunEstimate FitGameSky(double elevation, double azimuth, bool* refused) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(elevation, azimuth);
  const ImageRGB img = RenderGameSky(sun);
  const auto mask = MaskDisc(img.width, img.height, sun, 15.0);
  const SkySunEstimate e = FitSunFromSky(img, mask, SkySunOptions{});
  std::string why;
  *refused = !EstimateSunFromSky(img, mask, SkySunOptions{}, &why).has_value();
  std::printf("game model el %g az %g: estimate el %.2f az %.2f, error %.3f deg, uncertainty %.3f deg (el %.3f, az "
              "%.3f), type %d, log RMSE %.4f (at the truth %.4f)%s\n",
              elevation, azimuth, e.elevation_deg, e.azimuth_deg, AngleDeg(e.direction, sun), e.uncertainty_deg,
              e.elevation_uncertainty_deg, e.azimuth_uncertainty_deg, e.sky_type, e.log_rmse,
              SkyFitCostAt(img, mask, SkySunOptions{}, sun), *refused ? ", refused" : "");
  return e;
}

TEST(SkySun, GameSkyModelHighSun) {
  bool refused = true;
  const SkySunEstimate e = FitGameSky(35.3, 121.4, &refused);
  const double err = AngleDeg(e.direction, latlong::DirectionFromElevationAzimuthDeg(35.3, 121.4));
  EXPECT_LT(err, 9.0);
  EXPECT_LE(err, e.uncertainty_deg);
  EXPECT_FALSE(refused);
}

TEST(SkySun, GameSkyModelLowSunGivesAzimuthFlagsElevation) {
  bool refused = false;
  const SkySunEstimate e = FitGameSky(6.7, -48.2, &refused);
  EXPECT_LT(std::abs(std::remainder(e.azimuth_deg + 48.2, 360.0)), 2.0);
  EXPECT_TRUE(e.elevation_at_bound);
  EXPECT_TRUE(refused);
}

TEST(SkySun, GameSkyModelSymmetricTwilightIsRefused) {
  bool refused = false;
  const SkySunEstimate e = FitGameSky(-3.8, 10.6, &refused);
  EXPECT_GT(e.uncertainty_deg, 90.0);
  EXPECT_TRUE(refused);
}

// The wrong control: the CIE overcast sky (type 1) has no azimuthal structure, so every sun
// fits alike; the uncertainty spans the sky and EstimateSunFromSky refuses.
TEST(SkySun, OvercastSkyGivesNoDirection) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(40, 45);
  const ImageRGB img = RenderCie(1, sun, 0.02);
  const SkySunEstimate e = FitSunFromSky(img, {}, SkySunOptions{});
  EXPECT_GT(e.uncertainty_deg, 90.0);
  std::string why;
  EXPECT_FALSE(EstimateSunFromSky(img, {}, SkySunOptions{}, &why).has_value());
  EXPECT_NE(why.find("max_uncertainty_deg"), std::string::npos) << why;
}

TEST(SkySun, OptionsAndInputErrorsNameTheField) {
  SkySunOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.cell_deg = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("SkySunOptions::cell_deg = 0"), std::string::npos) << why;
  o = SkySunOptions{};
  o.final_step_deg = 2.0;  // coarser than refine_step_deg
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("SkySunOptions::final_step_deg = 2"), std::string::npos) << why;
  const ImageRGB img = RenderCie(12, latlong::DirectionFromElevationAzimuthDeg(30, 0), 0.0, 64, 32);
  EXPECT_THROW(FitSunFromSky(img, std::vector<float>(5, 1.0f), SkySunOptions{}), Error);
  EXPECT_THROW(FitSunFromSky(img, std::vector<float>(64 * 32, 0.0f), SkySunOptions{}), Error);  // no sky
}

// Real photos: datasets/real/<name>.exr (SKYCAL=build/skycal bash datasets/fetch_real_skies.sh
// --with-npm). The visible sun (capture::DetectSun) is the truth; the sky the estimate sees
// leaves out 15 deg around it, the ground (rows below the horizon) and, where a hand mask
// exists (datasets/masks/<name>_mask.exr, R < 0.5 is not sky), what it marks.
struct RealResult {
  bool ran = false;
  double error_deg = 0.0;
  SkySunEstimate estimate;
};

RealResult RunReal(const std::string& name) {
  RealResult r;
  const std::string path = std::string(SKYCAL_SOURCE_DIR) + "/datasets/real/" + name + ".exr";
  if (!std::filesystem::exists(path)) return r;
  const ImageRGB img = ReadExrRGB(path).image;
  std::string why;
  const auto sun = capture::DetectSun(img, &why);
  if (!sun) throw Error(path + ": no visible sun to compare with: " + why);
  std::vector<float> mask;
  const std::string mask_path = std::string(SKYCAL_SOURCE_DIR) + "/datasets/masks/" + name + "_mask.exr";
  if (std::filesystem::exists(mask_path)) {
    int w = 0, h = 0;
    mask = ReadExrChannel(mask_path, "R", &w, &h);
    if (w != img.width || h != img.height) throw Error(mask_path + ": size differs from " + path);
  }
  mask = MaskDisc(img.width, img.height, sun->direction, 15.0, mask);
  r.estimate = FitSunFromSky(img, mask, SkySunOptions{});
  r.error_deg = AngleDeg(r.estimate.direction, sun->direction);
  r.ran = true;
  std::printf("%s: truth el %.2f az %.2f; estimate el %.2f az %.2f, error %.2f deg, uncertainty %.2f deg, type %d, "
              "log RMSE %.3f, %d cells\n",
              name.c_str(), latlong::ElevationDeg(sun->direction), latlong::AzimuthDeg(sun->direction),
              r.estimate.elevation_deg, r.estimate.azimuth_deg, r.error_deg, r.estimate.uncertainty_deg,
              r.estimate.sky_type, r.estimate.log_rmse, r.estimate.cells);
  return r;
}

// The method's constants were fixed on synthetic skies before any photo was run; sunrise is
// the development photo, sunset and sky are held out (bench/results/sky_sun.md). Thresholds:
// the error measured plus a margin, and the uncertainty covering the error where it did.
TEST(SkySun, RealSunrise) {
  const RealResult r = RunReal("sunrise");
  if (!r.ran) GTEST_SKIP() << "datasets/real/sunrise.exr is absent (datasets/fetch_real_skies.sh --with-npm)";
  EXPECT_LT(r.error_deg, 3.0);
  EXPECT_LE(r.error_deg, r.estimate.uncertainty_deg);
}

TEST(SkySun, RealSunsetHeldOut) {
  const RealResult r = RunReal("sunset");
  if (!r.ran) GTEST_SKIP() << "datasets/real/sunset.exr is absent (datasets/fetch_real_skies.sh --with-npm)";
  EXPECT_LT(r.error_deg, 6.0);
  EXPECT_LE(r.error_deg, r.estimate.uncertainty_deg);
}

TEST(SkySun, RealSkyHeldOut) {
  const RealResult r = RunReal("sky");
  if (!r.ran) GTEST_SKIP() << "datasets/real/sky.exr is absent (datasets/fetch_real_skies.sh --with-npm)";
  // Broken bright cumulus around the sun: the models fit poorly (large log RMSE), the
  // uncertainty is wide (over max_uncertainty_deg: EstimateSunFromSky refuses) and covers
  // the error; the error bound is loose on purpose.
  EXPECT_LT(r.error_deg, 15.0);
  EXPECT_LE(r.error_deg, r.estimate.uncertainty_deg);
  EXPECT_GT(r.estimate.log_rmse, 0.2);
  EXPECT_GT(r.estimate.uncertainty_deg, SkySunOptions{}.max_uncertainty_deg);
}

// FindSun: the disc when the frame shows one; else the sky's pattern over the automatic sky
// mask (no hand mask, no disc region left out), within its uncertainty; else nothing, with
// both reasons (the overcast control).
TEST(SkySun, FindSunTakesTheDiscElseTheSky) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(35.3, 121.4);
  std::string why;
  // A disc of 3 x 3 pixels at 1e6 cd/m^2 (a 512 x 256 render's pixels are wider than the
  // sun's 0.53 degrees, so the renderer's own disc may fall between pixel centres).
  ImageRGB disc = RenderGameSky(sun);
  const auto px = latlong::PixelPosition(sun, disc.width, disc.height);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      for (int c = 0; c < 3; ++c)
        disc.at(static_cast<int>(std::lround(px[0])) + dx, static_cast<int>(std::lround(px[1])) + dy, c) = 1e6f;
  const auto with_disc = FindSun(disc, 20.0, SkySunOptions{}, &why);
  ASSERT_TRUE(with_disc.has_value()) << why;
  EXPECT_EQ(with_disc->source, "disc");
  EXPECT_LT(AngleDeg(with_disc->direction, sun), 1.0);
  const auto hidden = FindSun(RenderGameSky(sun), 20.0, SkySunOptions{}, &why);
  ASSERT_TRUE(hidden.has_value()) << why;
  EXPECT_EQ(hidden->source, "sky");
  EXPECT_FALSE(hidden->disc_refusal.empty());
  const double err = AngleDeg(hidden->direction, sun);
  std::printf("FindSun without a disc: error %.2f deg, uncertainty %.2f deg\n", err, hidden->uncertainty_deg);
  EXPECT_LE(err, hidden->uncertainty_deg);
  EXPECT_LT(err, 12.0);
  const auto overcast = FindSun(RenderCie(1, sun, 0.02), 20.0, SkySunOptions{}, &why);
  EXPECT_FALSE(overcast.has_value());
  EXPECT_NE(why.find("no sun disc"), std::string::npos) << why;
  EXPECT_NE(why.find("the sky does not place the sun"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal::skysun
