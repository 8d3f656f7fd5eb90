// Synthetic round trips: render known parameters, fit from a perturbed start, compare.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/renderer.h"
#include "skycal/testing/synthetic_sky.h"
#include "test_util.h"

namespace skycal {
namespace {

using render::ModelVariant;

render::Preset Truth(ModelVariant variant) { return synthetic::TruthPreset(variant); }

render::Preset Perturbed(const render::Preset& truth, unsigned seed, double amplitude, double dg) {
  return synthetic::PerturbedStart(truth, seed, amplitude, dg);
}

std::string WriteReference(const testing::ScratchDir& dir, const std::string& name, const render::Preset& truth,
                           double elevation, double azimuth, int width, double noise = 0.0, double outliers = 0.0,
                           unsigned seed = 1) {
  const std::string path = dir / (name + ".exr");
  synthetic::WriteSyntheticReference(path, truth, elevation, azimuth, width, noise, outliers, seed);
  return path;
}

fit::FitOptions Options(ModelVariant variant, render::Backend backend) {
  fit::FitOptions o;
  o.variant = variant;
  o.backend = backend;
  o.verbose = false;
  return o;
}

TEST(FitRoundTrip, NoiselessRecoversImageAndHaziness) {
  testing::ScratchDir dir("fit-noiseless");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  for (ModelVariant variant : {ModelVariant::kFfxv, ModelVariant::kFfxvIso}) {
    const render::Preset truth = Truth(variant);
    for (double el : {-4.0, 8.0, 35.0, 70.0}) {
      SCOPED_TRACE(std::string(render::ToString(variant)) + " elevation " + std::to_string(el));
      const std::string ref_path = WriteReference(dir, "ref", truth, el, 30.0, 256);
      const fit::FitOptions o = Options(variant, render::Backend::kCpu);
      const fit::Reference ref = fit::LoadReference(ref_path, o);
      const fit::FitResult r = fit::FitSky({ref}, Perturbed(truth, 3, 0.2, 0.06), o, *cpu);
      std::cout << "[roundtrip] " << render::ToString(variant) << " el " << el << " rel_rmse "
                << r.references[0].errors.rel_rmse << " g " << r.preset.haziness_g << " iterations " << r.iterations
                << " time " << r.time_s << " s\n";
      EXPECT_LT(r.references[0].errors.rel_rmse, 1e-4);
      EXPECT_NEAR(r.preset.haziness_g, truth.haziness_g, 0.005);
    }
  }
}

TEST(FitRoundTrip, VulkanAndCpuBackendsReachTheSameFit) {
  testing::ScratchDir dir("fit-backends");
  const render::Preset truth = Truth(ModelVariant::kFfxvIso);
  const std::string ref_path = WriteReference(dir, "ref", truth, 25.0, -60.0, 256);
  fit::FitResult results[2];
  int k = 0;
  for (auto backend : {render::Backend::kCpu, render::Backend::kVulkan}) {
    auto renderer = render::CreateRenderer(backend);
    const fit::FitOptions o = Options(ModelVariant::kFfxvIso, backend);
    results[k++] = fit::FitSky({fit::LoadReference(ref_path, o)}, Perturbed(truth, 4, 0.2, -0.05), o, *renderer);
  }
  // Same optimum within float rounding of the Vulkan objective: g to 1e-4, images to 1e-4.
  EXPECT_NEAR(results[0].preset.haziness_g, results[1].preset.haziness_g, 1e-4);
  // Compared on the fitted pixels (sky, outside the sun cone): elsewhere (ground lit by
  // the whole sky, the two horizon columns) only the weak priors hold the LUT.
  const fit::Reference ref = fit::LoadReference(ref_path, Options(ModelVariant::kFfxvIso, render::Backend::kCpu));
  double worst = 0.0;
  const auto& a = results[0].references[0].rendered.pixels;
  const auto& b = results[1].references[0].rendered.pixels;
  for (size_t i = 0; i < ref.pixel_class.size(); ++i) {
    if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
    for (int c = 0; c < 3; ++c) worst = std::max<double>(worst, std::abs(a[3 * i + c] - b[3 * i + c]) / a[3 * i + c]);
  }
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(results[1].references[0].errors.rel_rmse, 1e-4);
  std::cout << "[backends] g cpu " << results[0].preset.haziness_g << " vulkan " << results[1].preset.haziness_g
            << " max image difference " << worst << "\n";
}

TEST(FitRoundTrip, NoiseAndOutliersAreHandledByTheRobustLoss) {
  testing::ScratchDir dir("fit-noise");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const render::Preset truth = Truth(ModelVariant::kFfxvIso);
  const std::string clean = WriteReference(dir, "clean", truth, 30.0, 10.0, 256);
  const std::string noisy = WriteReference(dir, "noisy", truth, 30.0, 10.0, 256, 0.02, 0.05, 9);
  const fit::FitOptions o = Options(ModelVariant::kFfxvIso, render::Backend::kCpu);
  const fit::FitResult r = fit::FitSky({fit::LoadReference(noisy, o)}, Perturbed(truth, 5, 0.2, 0.05), o, *cpu);
  // Compare the fit with the clean truth: the noise must not be fitted.
  const fit::ImageErrors e = fit::CompareToReference(fit::LoadReference(clean, o), r.references[0].rendered);
  std::cout << "[noise] rel_rmse vs clean " << e.rel_rmse << " g " << r.preset.haziness_g << "\n";
  // Tolerances: 2% pixel noise averages down over ~10^2 pixels per LUT column and row
  // (measured 0.16%), and the Cauchy loss (scale 5%) gives a 5x outlier the weight
  // rho' = 1/1000 (its pull ~1/16 of a pixel 5% off); 0.5% leaves 3x margin.
  EXPECT_LT(e.rel_rmse, 0.005);
  EXPECT_NEAR(r.preset.haziness_g, truth.haziness_g, 0.02);
}

// The day's linear start (fit/src/linear_stage.h): g is searched by six references spread
// over the sun angles and held at the median of theirs by the others; the day still
// recovers g and fits every frame. 9 frames of 64x32: fast.
TEST(FitRoundTrip, DayStartSearchesGOnSixReferencesAndHoldsItOnTheRest) {
  testing::ScratchDir dir("fit-day-g");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const render::Preset truth = Truth(ModelVariant::kFfxv);
  fit::FitOptions o = Options(ModelVariant::kFfxv, render::Backend::kCpu);
  std::vector<fit::Reference> refs;
  const double elevations[] = {3, 8, 14, 21, 29, 38, 48, 59, 71};
  for (int i = 0; i < 9; ++i) {
    refs.push_back(fit::LoadReference(
        WriteReference(dir, "ref" + std::to_string(i), truth, elevations[i], 20.0 * i - 80.0, 64), o));
  }
  const fit::FitResult r = fit::FitSky(refs, Perturbed(truth, 5, 0.2, 0.05), o, *cpu);
  ASSERT_TRUE(r.linear_start.day.has_value());
  const auto& starts = r.linear_start.day->references;
  ASSERT_EQ(starts.size(), 9u);
  // A g search costs two solves per scan node (9 nodes) and more for its golden sections:
  // the six searching starts take >= 18 solves more than the held ones.
  int fewest = 1 << 30;
  for (const auto& [name, single] : starts) fewest = std::min(fewest, single.solves);
  int searched = 0, held = 0;
  for (const auto& [name, single] : starts) {
    searched += single.solves >= fewest + 18;
    held += single.solves == fewest;
    // A held start carries the day's g (a searched one its own).
    if (single.solves == fewest) EXPECT_EQ(single.haziness_g, r.linear_start.day->haziness_g) << name;
  }
  EXPECT_EQ(searched, 6);
  EXPECT_EQ(held, 3);
  // Tolerances: the frames are the truth's own renders (the ceiling is 0); 64x32 leaves
  // ~10 pixels per LUT column near the sun, so g is found to ~1e-2, each frame to ~0.1%.
  EXPECT_NEAR(r.preset.haziness_g, truth.haziness_g, 0.02);
  for (const auto& f : r.references) EXPECT_LT(f.errors.rel_rmse, 2e-3);
}

TEST(FitRoundTrip, SyntheticDayRecoversTheObservedLut) {
  testing::ScratchDir dir("fit-day");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const render::Preset truth = Truth(ModelVariant::kFfxv);
  fit::FitOptions o = Options(ModelVariant::kFfxv, render::Backend::kCpu);
  o.absolute = true;
  std::vector<fit::Reference> refs;
  const double elevations[] = {-3, 1, 4, 8, 13, 19, 26, 34, 43, 53, 64, 76};
  for (int i = 0; i < 12; ++i) {
    refs.push_back(fit::LoadReference(
        WriteReference(dir, "ref" + std::to_string(i), truth, elevations[i], 15.0 * i - 80.0, 128), o));
  }
  const fit::FitResult r = fit::FitSky(refs, Perturbed(truth, 6, 0.2, 0.0), o, *cpu);
  // LUT rows between the lowest and highest sun: each fitted entry against the truth,
  // over columns a pixel of a 128x64 reference reaches (sin(elevation) >= 1/40).
  std::vector<double> errors;
  const auto& g = truth.luts.grid;
  const int first = static_cast<int>(r.references.back().observed_rows.front());
  const int last = static_cast<int>(r.references.front().observed_rows.back());
  for (int row = first; row <= last; ++row)
    for (int col = 2; col < g.n_gamma; ++col)
      for (int ch = 0; ch < 3; ++ch) {
        const size_t i = (static_cast<size_t>(row) * g.n_gamma + col) * 3 + ch;
        const double t = truth.luts.rayleigh[i] + truth.luts.mie[i];
        const double f = r.preset.luts.rayleigh[i] + r.preset.luts.mie[i];
        errors.push_back(std::abs(f / t - 1.0));
      }
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
  double worst_image = 0.0;
  for (size_t i = 0; i < r.references.size(); ++i) {
    worst_image = std::max(worst_image, r.references[i].errors.rel_rmse);
    std::cout << "[day] elevation " << elevations[i] << " rel_rmse " << r.references[i].errors.rel_rmse << "\n";
  }
  std::cout << "[day] rows " << first << ".." << last << " median LUT error " << median << " p90 " << p90
            << " worst image rel_rmse " << worst_image << " time " << r.time_s << " s\n";
  EXPECT_LT(median, 0.01);
  EXPECT_LT(p90, 0.05);
  EXPECT_LT(worst_image, 1e-3);
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

TEST(FitReference, ClipDetectionFindsClampsButNotUniformSkies) {
  testing::ScratchDir dir("clip");
  fit::FitOptions o;
  o.sun_dir = latlong::DirectionFromElevationAzimuthDeg(40.0, 0.0);
  // A uniform sky: large equal regions are not a clamp.
  capture::LatLongFrame f;
  f.radiance = ImageRGB(128, 64);
  std::fill(f.radiance.pixels.begin(), f.radiance.pixels.end(), 3000.0f);
  capture::WriteLatLongFrame(dir / "uniform.exr", f);
  const fit::Reference u = fit::LoadReference(dir / "uniform.exr", o);
  EXPECT_EQ(u.clip_level, 0.0);
  EXPECT_EQ(u.counts.clipped, 0);
  // A sky with a clamped sun (Blender's studio lights clamp it at 32000): masked.
  for (int y = 20; y < 24; ++y)
    for (int x = 60; x < 66; ++x)
      for (int c = 0; c < 3; ++c) f.radiance.at(x, y, c) = 32000.0f;
  for (int c = 0; c < 3; ++c) f.radiance.at(10, 10, c) = 31500.0f;  // 98.4% of the clamp: masked too
  capture::WriteLatLongFrame(dir / "clamped.exr", f);
  fit::FitOptions far = o;
  far.sun_dir = latlong::DirectionFromElevationAzimuthDeg(80.0, 90.0);  // cone away from the clamp
  const fit::Reference c = fit::LoadReference(dir / "clamped.exr", far);
  EXPECT_EQ(c.clip_level, 32000.0);
  EXPECT_EQ(c.counts.clipped, 25);
}

}  // namespace
}  // namespace skycal
