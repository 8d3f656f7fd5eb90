// Real photographed skies: `skycal import`'s mapping of Blender / Poly Haven panoramas onto
// the project's lat-long convention (synthetic, always run), and fits of the model to two
// real frames fetched by datasets/fetch_real_skies.sh (skipped when they are absent).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "import_verb.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/latlong_import.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "test_util.h"

namespace skycal {
namespace {

constexpr double kPi = std::numbers::pi;
const std::string kSourceDir = SKYCAL_SOURCE_DIR;

// Blender world direction of texel (i, j) of a W x H equirectangular image: the inverse of
// u = -atan2(y, x) / (2 pi) + 0.5, v = atan2(z, hypot(x, y)) / pi + 0.5 (v up), sampled at
// texel centres u = (i + 0.5) / W, v = 1 - (j + 0.5) / H.
std::array<double, 3> BlenderTexelDirection(int i, int j, int w, int h) {
  const double u = (i + 0.5) / w, v = 1.0 - (j + 0.5) / h;
  const double azimuth = 2.0 * kPi * (0.5 - u), elevation = kPi * (v - 0.5);
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
}

// A Blender-convention image whose channels are 2 + the Blender direction's x, y, z.
ImageRGB BlenderDirectionImage(int w, int h) {
  ImageRGB img(w, h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const auto b = BlenderTexelDirection(i, j, w, h);
      for (int c = 0; c < 3; ++c) img.at(i, j, c) = static_cast<float>(2.0 + b[c]);
    }
  return img;
}

TEST(ImportMapping, BlenderAxesMapToProjectAxes) {
  // Blender +X (image centre) -> +Z (longitude 0), +Y -> +X (longitude 90), +Z (up) -> +Y.
  EXPECT_EQ(capture::BlenderToProjectDirection({1, 0, 0}), (std::array<double, 3>{0, 0, 1}));
  EXPECT_EQ(capture::BlenderToProjectDirection({0, 1, 0}), (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(capture::BlenderToProjectDirection({0, 0, 1}), (std::array<double, 3>{0, 1, 0}));
}

TEST(ImportMapping, ResamplesBlenderPanoramaOntoProjectNodes) {
  // Every output node must hold the source's value for the same physical direction: with
  // channels = 2 + blender direction, node d must read 2 + (d.z, d.x, d.y). Any mirror,
  // half-turn or half-texel shift would show up as an error of order 0.1 or more.
  const int w = 128, h = 64;
  const ImageRGB out = capture::ResampleToProjectLatLong(BlenderDirectionImage(w, h), capture::SourceConvention::kBlender, w, h);
  ASSERT_EQ(out.width, w);
  ASSERT_EQ(out.height, h);
  double worst = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto d = latlong::PixelDirection(x, y, w, h);
      const double want[3] = {2.0 + d[2], 2.0 + d[0], 2.0 + d[1]};
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.at(x, y, c) - want[c]));
    }
  // Bilinear interpolation of a unit-sphere coordinate on a 2.8 deg grid: ~(dx^2 / 8) = 3e-4,
  // plus the half-texel clamp at the poles.
  EXPECT_LT(worst, 2e-3);
}

TEST(ImportMapping, ExrConventionSameSizeIsACopy) {
  ImageRGB src(64, 32);
  for (size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = static_cast<float>(0.5 + (i * 7919 % 1000) / 100.0);
  // Rows 0 and H-1 (poles) become their means; columns 0 and W-1 (seam) are the same direction.
  const ImageRGB out = capture::ResampleToProjectLatLong(src, capture::SourceConvention::kExr, 64, 32);
  for (int y = 1; y < 31; ++y)
    for (int x = 0; x < 63; ++x)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(out.at(x, y, c), src.at(x, y, c)) << x << "," << y << "," << c;
}

TEST(ImportVerb, DetectsTheSunInTheProjectFrameAndRecordsProvenance) {
  testing::ScratchDir dir("import-sun");
  const int w = 256, h = 128;
  ImageRGB img(w, h);
  // A sun at Blender azimuth 60 deg (from +X toward +Y), elevation 20 deg, on a dim sky.
  const double az = 60.0 * kPi / 180.0, el = 20.0 * kPi / 180.0;
  const std::array<double, 3> sun_b = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const auto b = BlenderTexelDirection(i, j, w, h);
      const double cosang = b[0] * sun_b[0] + b[1] * sun_b[1] + b[2] * sun_b[2];
      const float v = cosang > std::cos(1.5 * kPi / 180.0) ? 5000.0f : 1.0f;
      for (int c = 0; c < 3; ++c) img.at(i, j, c) = v;
    }
  img.at(5, 100, 1) = -0.25f;  // DWAB-like ringing: kept and counted
  WriteExrRGB(dir / "src.exr", img, {}, ExrPixelType::kHalf);

  controllers::ImportOptions o;
  o.in_path = dir / "src.exr";
  o.out_path = dir / "frame.exr";
  o.detect_sun = true;
  const nlohmann::json s = cli::RunImportImpl(o);
  const auto want = capture::BlenderToProjectDirection(sun_b);
  const capture::LatLongFrame f = capture::ReadLatLongFrame(o.out_path);
  ASSERT_TRUE(f.sun_direction.has_value());
  const auto& got = *f.sun_direction;
  const double angle = std::acos(std::min(1.0, got[0] * want[0] + got[1] * want[1] + got[2] * want[2])) * 180.0 / kPi;
  EXPECT_LT(angle, 0.5) << s.dump(2);
  EXPECT_NEAR(s["sun"]["elevation_deg"].get<double>(), 20.0, 0.5);
  EXPECT_NEAR(s["sun"]["azimuth_deg"].get<double>(), 60.0, 0.5);  // Blender +Y side = longitude +90
  EXPECT_EQ(s["pixels"]["source"]["negative"].get<long long>(), 1);
  EXPECT_EQ(f.extra.strings.at("skycalSourceConvention"), "blender");
  EXPECT_EQ(f.extra.strings.at("skycalSource").rfind("src.exr sha256:", 0), 0u);
}

TEST(ImportVerb, RefusesWhenNoDistinctSunAndWritesNothing) {
  testing::ScratchDir dir("import-nosun");
  ImageRGB img(64, 32);
  for (float& v : img.pixels) v = 3.0f;  // overcast: no sun
  WriteExrRGB(dir / "src.exr", img, {});
  controllers::ImportOptions o;
  o.in_path = dir / "src.exr";
  o.out_path = dir / "frame.exr";
  o.detect_sun = true;
  EXPECT_THROW(cli::RunImportImpl(o), Error);
  EXPECT_FALSE(std::filesystem::exists(o.out_path));
  EXPECT_EQ(dir.CountEntries(), 1);  // only the source: no temporary left behind
}

// --- real skies ----------------------------------------------------------------------------

struct RealFit {
  fit::Reference ref;
  fit::ReferenceFit fit;
};

RealFit FitRealSky(const std::string& name) {
  fit::FitOptions o;
  o.variant = render::ModelVariant::kFfxvIso;
  o.backend = render::Backend::kCpu;
  o.verbose = false;
  // Buildings, trees, pylons and wires above the horizon, and the lowest 3.3 deg (haze,
  // distant shore, fog); see datasets/README.md.
  o.mask_path = kSourceDir + "/datasets/masks/" + name + "_mask.exr";
  const render::Preset init = render::LoadPreset(kSourceDir + "/datasets/presets/default_clear.json");
  RealFit r{fit::LoadReference(kSourceDir + "/datasets/real/" + name + ".exr", o), {}};
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  r.fit = fit::FitSky({r.ref}, init, o, *cpu).references.at(0);
  std::cout << "[ real sky ] " << name << ": rel_rmse " << r.fit.errors.rel_rmse << ", log_rmse "
            << r.fit.errors.log_rmse << ", " << r.ref.counts.sky << " sky pixels fitted, " << r.ref.counts.user_masked
            << " user-masked, sun elevation " << latlong::ElevationDeg(r.ref.sun_dir) << " deg\n";
  return r;
}

bool RealSkiesPresent() { return std::filesystem::exists(kSourceDir + "/datasets/real/sunrise.exr"); }
constexpr const char* kFetchHint =
    "datasets/real/sunrise.exr is absent: run datasets/fetch_real_skies.sh to fetch the real HDR skies";

// Thresholds = measured x 1.5 (cpu backend, the bundled default preset as the start, the committed masks):
// sunrise rel 3.36% / log 0.0345, sunset rel 4.57% / log 0.0417 with the coarse-to-fine Ceres fit; the
// linear start measures sunrise 3.41% / 0.0333, sunset 4.41% / 0.0402 (thresholds kept). A real sky cannot be
// matched exactly by this model: its LUTs depend on sun zenith and view elevation only, and
// azimuth enters solely through the Rayleigh and Cornette-Shanks phase functions of the
// scattering angle, so azimuthal structure that is not a function of that angle (thin
// cloud and haze patches, the horizon's uneven aerosol layer, multiply scattered light off
// uneven terrain) stays in the residual; so do lossy DWAB compression
// (+-1-2%), stitching and vignetting of the source photographs, and the unmasked faint
// power lines beside the sunrise sun. The margin covers platform floating-point and
// Ceres/Eigen differences in where the iterations stop (both fits end at the iteration cap).
TEST(RealSky, FitsSunrise) {
  if (!RealSkiesPresent()) GTEST_SKIP() << kFetchHint;
  const RealFit r = FitRealSky("sunrise");
  EXPECT_EQ(r.ref.sun_source, "attribute");  // recorded by `skycal import --detect-sun`
  EXPECT_NEAR(latlong::ElevationDeg(r.ref.sun_dir), 8.1, 0.2);
  EXPECT_GT(r.ref.counts.sky, 150000);  // the mask leaves most of the sky
  EXPECT_LT(r.fit.errors.rel_rmse, 0.050);
  EXPECT_LT(r.fit.errors.log_rmse, 0.052);
}

TEST(RealSky, FitsSunset) {
  if (!RealSkiesPresent()) GTEST_SKIP() << kFetchHint;
  ASSERT_TRUE(std::filesystem::exists(kSourceDir + "/datasets/real/sunset.exr"))
      << "datasets/real/sunset.exr is absent: run datasets/fetch_real_skies.sh";
  const RealFit r = FitRealSky("sunset");
  EXPECT_EQ(r.ref.sun_source, "attribute");
  EXPECT_NEAR(latlong::ElevationDeg(r.ref.sun_dir), 3.35, 0.2);
  EXPECT_GT(r.ref.counts.sky, 150000);
  EXPECT_LT(r.fit.errors.rel_rmse, 0.069);
  EXPECT_LT(r.fit.errors.log_rmse, 0.063);
}

// One answer whatever the backend, on a real sky with nothing masked (trees and pylons
// left in, as a new user's photograph would be). The linear start solves in double on the
// host for both backends; the backend draws the result and checks it (render_check), so
// the presets must agree to float rounding. Before the linear start the two backends'
// Ceres solves ended 16% RMS apart on this sky (LUT entries up to 99% apart): the data do
// not determine some directions, and float-vs-double rounding picked among them. The
// damped solve (LinearSkyOptions::damping) makes the solution unique.
TEST(RealSky, BackendsAgreeOnTheUnmaskedSunrise) {
  if (!RealSkiesPresent()) GTEST_SKIP() << kFetchHint;
  const render::Preset init = render::LoadPreset(kSourceDir + "/datasets/presets/default_clear.json");
  fit::FitResult results[2];
  fit::Reference ref;
  int k = 0;
  for (auto backend : {render::Backend::kCpu, render::Backend::kVulkan}) {
    fit::FitOptions o;
    o.backend = backend;
    o.verbose = false;
    ref = fit::LoadReference(kSourceDir + "/datasets/real/sunrise.exr", o);
    auto renderer = render::CreateRenderer(backend);
    results[k++] = fit::FitSky({ref}, init, o, *renderer);
  }
  double sq = 0.0, worst = 0.0;
  long long n = 0;
  const auto& a = results[0].references[0].rendered.pixels;
  const auto& b = results[1].references[0].rendered.pixels;
  for (size_t i = 0; i < ref.pixel_class.size(); ++i) {
    if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
    for (int c = 0; c < 3; ++c) {
      const double d = (b[3 * i + c] - a[3 * i + c]) / a[3 * i + c];
      sq += d * d;
      worst = std::max(worst, std::abs(d));
      ++n;
    }
  }
  double lut_worst = 0.0;
  for (size_t i = 0; i < results[0].preset.luts.mie.size(); ++i) {
    for (const auto& [x, y] : {std::pair{results[0].preset.luts.rayleigh[i], results[1].preset.luts.rayleigh[i]},
                               std::pair{results[0].preset.luts.mie[i], results[1].preset.luts.mie[i]},
                               std::pair{results[0].preset.luts.isotropic[i], results[1].preset.luts.isotropic[i]}}) {
      if (x > 0.0f) lut_worst = std::max(lut_worst, std::abs(static_cast<double>(y) / x - 1.0));
    }
  }
  std::cout << "[ real sky ] unmasked sunrise, cpu vs vulkan: RMS " << std::sqrt(sq / n) << ", worst " << worst
            << ", LUT worst " << lut_worst << ", g " << results[0].preset.haziness_g << " / "
            << results[1].preset.haziness_g << "\n";
  // Float rendering of the same preset: the parity bound (2e-5, render_parity_test.cc).
  EXPECT_LT(std::sqrt(sq / n), 2e-5);
  EXPECT_LT(worst, 2e-5);
  EXPECT_EQ(results[0].preset.haziness_g, results[1].preset.haziness_g);
  EXPECT_EQ(lut_worst, 0.0);
}

}  // namespace
}  // namespace skycal
