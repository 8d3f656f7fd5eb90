// The fit against the model's own ceiling (fit/include/skycal/fit/ceiling.h) on clear skies
// the bundled preset was not built from, started where a user starts: the bundled default
// preset, default options (ffxv-iso, Cauchy loss, linear start, Vulkan render check).
//
// Criterion (issue "fit: robust and fast"): fit rel_rmse <= 1.2 x LUT ceiling + 0.1%.
// Why that slack: the fit minimises the robust log error, the ceiling the plain relative
// error (what rel_rmse reports); where the model misfits by 10-20% near the sun the two
// optima differ by up to ~10% of the error, and the weak priors (1e-8) add ~0.05% on
// near-perfect fits. A fit that abandons a region (the failure this guards against) ends at
// 2-20x its ceiling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "skycal/render/renderer.h"
#include "test_util.h"

namespace skycal {
namespace {

constexpr int kWidth = 256;  // 256 x 128 references: the CIE benchmark's size

render::Preset DefaultStart() {
  return render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
}

fit::FitOptions Defaults() {
  fit::FitOptions o;
  o.verbose = false;
  return o;
}

struct Outcome {
  double fit = 0.0, ceiling = 0.0, per_row = 0.0;
};

Outcome FitAndCeiling(const std::string& path, render::SkyRenderer& renderer) {
  const fit::FitOptions o = Defaults();
  const fit::Reference ref = fit::LoadReference(path, o);
  const fit::FitResult r = fit::FitSky({ref}, DefaultStart(), o, renderer);
  const fit::CeilingResult c = fit::ModelCeiling(ref, DefaultStart(), o);
  // More freedom never fits worse in exact arithmetic; slack for the g search (each
  // ceiling searches its own g, to ~1e-4) and the floor on non-positive entries, which
  // bind differently in the two (measured: up to 10% apart at a -5 deg twilight sky). Since
  // the pull toward the start has a floor (linear_sky.cc kPullFloorShare), a table the start
  // makes vanishing at a twilight sun is no longer pinned to it: at the turbid -5 deg sky,
  // whose Mie is 1e-6 of its Rayleigh, the per-row ceiling is 0.024% against the LUT's
  // 0.017%, both far under any fit's error, hence 1e-4 absolute.
  EXPECT_LE(c.per_row_rel_rmse, c.lut_rel_rmse * 1.2 + 1e-4) << path;
  return {r.references[0].errors.rel_rmse, c.lut_rel_rmse, c.per_row_rel_rmse};
}

void Summarise(const char* what, std::vector<double> ratios) {
  std::sort(ratios.begin(), ratios.end());
  std::cout << "[ceiling] " << what << ": fit / ceiling median " << ratios[ratios.size() / 2] << ", p90 "
            << ratios[ratios.size() * 9 / 10] << ", worst " << ratios.back() << " over " << ratios.size() << " skies\n";
}

void ExpectAtCeiling(const Outcome& r, const std::string& what) {
  std::cout << "[ceiling] " << what << ": fit " << 100 * r.fit << "%  LUT ceiling " << 100 * r.ceiling
            << "%  per-row ceiling " << 100 * r.per_row << "%\n";
  EXPECT_LE(r.fit, 1.2 * r.ceiling + 0.001) << what;
}

TEST(FitCeiling, OwnFamilyCeilingIsZero) {
  // The preset's own render: the LUT ceiling is exact (float EXR storage: ~1e-7).
  testing::ScratchDir dir("ceiling-own");
  const std::string path = dir / "own.exr";
  refsky::WriteModelReference(path, DefaultStart(), latlong::DirectionFromElevationAzimuthDeg(25.0, 40.0), kWidth);
  fit::FitOptions o = Defaults();
  o.variant = render::ModelVariant::kFfxv;
  const fit::CeilingResult c = fit::ModelCeiling(fit::LoadReference(path, o), DefaultStart(), o);
  EXPECT_LT(c.lut_rel_rmse, 1e-5);
  EXPECT_NEAR(c.lut_g, 0.8, 2e-3);
}

TEST(FitCeiling, CieGeneralSkiesAtTenThirtySixtyDegrees) {
  testing::ScratchDir dir("ceiling-cie");
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  std::vector<double> ratios;
  for (const refsky::CieSkyType& t : refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath())) {
    for (double el : {10.0, 30.0, 60.0}) {
      const std::string path = dir / ("cie" + std::to_string(t.type) + "_" + std::to_string(int(el)) + ".exr");
      refsky::WriteCieReference(path, t, latlong::DirectionFromElevationAzimuthDeg(el, 0.0), kWidth);
      const Outcome r = FitAndCeiling(path, *vulkan);
      ExpectAtCeiling(r, "CIE type " + std::to_string(t.type) + " sun " + std::to_string(int(el)) + " deg");
      ratios.push_back(r.fit / std::max(r.ceiling, 1e-6));
    }
  }
  Summarise("CIE general skies", ratios);
}

TEST(FitCeiling, OtherAtmospheresFromLowToHighSuns) {
  testing::ScratchDir dir("ceiling-bakes");
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  std::vector<double> ratios;
  for (const refsky::AtmosphereVariant& v : refsky::StandardAtmosphereVariants()) {
    const render::Preset truth = refsky::BakeVariant(v);
    for (double el : {-5.0, 2.0, 10.0, 30.0, 60.0, 85.0}) {
      const std::string path = dir / (v.name + "_" + std::to_string(int(el)) + ".exr");
      refsky::WriteModelReference(path, truth, latlong::DirectionFromElevationAzimuthDeg(el, 70.0), kWidth);
      const Outcome r = FitAndCeiling(path, *vulkan);
      ExpectAtCeiling(r, v.name + " sun " + std::to_string(int(el)) + " deg");
      ratios.push_back(r.fit / std::max(r.ceiling, 1e-6));
    }
  }
  Summarise("baked atmospheres", ratios);
}

// Clouds and a building: contaminated pixels must not pull the fit. Measured against the
// clean sky, whose ceiling is ~0: the soft cloud edges (1x-1.3x the sky, within a few loss
// scales) legitimately keep some pull, the cores (3x: Cauchy weight ~1/(1 + (ln 3 /
// 0.05)^2) ~ 2e-3) and the building (0.15x) almost none. Measured 0.47%; a fit pulled by
// the contamination ends at 1.3-13% (the earlier strategies' numbers on this sky).
// Threshold 1%: 2x the measured value.
TEST(FitCeiling, CloudBlobsAndABuildingDoNotPull) {
  testing::ScratchDir dir("ceiling-outliers");
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  const render::Preset truth = refsky::BakeVariant(refsky::StandardAtmosphereVariants()[1]);
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(35.0, -20.0);
  const std::string clean = dir / "clean.exr", dirty = dir / "dirty.exr";
  refsky::WriteModelReference(clean, truth, sun, kWidth);
  capture::LatLongFrame f = capture::ReadLatLongFrame(clean);
  const int h = kWidth / 2;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long long touched = 0, sky = 0;
  // Six cumulus-like blobs (3x the sky, soft edges), 12-24 deg across, and a building:
  // 0.15x the sky from the horizon to 12 deg over 50 deg of azimuth.
  std::vector<std::array<double, 4>> blobs;  // direction, radius (rad)
  for (int i = 0; i < 6; ++i) {
    const auto d = latlong::DirectionFromElevationAzimuthDeg(10.0 + 60.0 * u(rng), 360.0 * u(rng));
    blobs.push_back({d[0], d[1], d[2], (12.0 + 12.0 * u(rng)) * M_PI / 360.0});
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const auto v = latlong::PixelDirection(x, y, kWidth, h);
      if (v[1] <= 0.0) continue;
      ++sky;
      double factor = 1.0;
      for (const auto& b : blobs) {
        const double ang = std::acos(std::clamp(v[0] * b[0] + v[1] * b[1] + v[2] * b[2], -1.0, 1.0));
        if (ang < b[3]) factor = std::max(factor, 1.0 + 2.0 * std::cos(0.5 * M_PI * ang / b[3]));
      }
      const double el = latlong::ElevationDeg(v), az = latlong::AzimuthDeg(v);
      if (el < 12.0 && az > 100.0 && az < 150.0) factor = 0.15;
      if (factor != 1.0) ++touched;
      for (int c = 0; c < 3; ++c) f.radiance.at(x, y, c) = static_cast<float>(f.radiance.at(x, y, c) * factor);
    }
  capture::WriteLatLongFrame(dirty, f);
  const fit::FitOptions o = Defaults();
  const fit::FitResult r = fit::FitSky({fit::LoadReference(dirty, o)}, DefaultStart(), o, *vulkan);
  const fit::Reference clean_ref = fit::LoadReference(clean, o);
  const double vs_clean = fit::CompareToReference(clean_ref, r.references[0].rendered).rel_rmse;
  const double ceiling = fit::ModelCeiling(clean_ref, DefaultStart(), o).lut_rel_rmse;
  std::cout << "[ceiling] clouds and building over " << 100.0 * touched / sky << "% of the sky: fit vs clean sky "
            << 100 * vs_clean << "%, clean ceiling " << 100 * ceiling << "%, loss scale "
            << r.linear_start.loss_scale() << "\n";
  EXPECT_GT(touched, sky / 20);  // the contamination is not negligible (> 5% of the sky)
  EXPECT_LE(vs_clean, 1.2 * ceiling + 0.01);
}

// The random-start stress study's CI subset (the full study: bench/bench_fit_stress.cc,
// bench/results/fit_stress.md): starts far from any sky (each LUT table x 10^U(-1, 1),
// g ~ U(0, 0.95)) on references whose exposure is off by 10^U(-3, 3); every fit must end
// finite and within 1.2 x its ceiling + 0.1%.
TEST(FitCeiling, RandomStartsReachTheCeiling) {
  testing::ScratchDir dir("ceiling-random");
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  std::vector<std::pair<std::string, std::string>> skies;  // name, path
  refsky::WriteCieReference(dir / "cie12.exr", types[11], latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0), kWidth);
  skies.emplace_back("CIE 12 sun 30", dir / "cie12.exr");
  refsky::WriteCieReference(dir / "cie1.exr", types[0], latlong::DirectionFromElevationAzimuthDeg(45.0, 90.0), kWidth);
  skies.emplace_back("CIE 1 sun 45", dir / "cie1.exr");
  refsky::WriteModelReference(dir / "hazy.exr", refsky::BakeVariant(refsky::StandardAtmosphereVariants()[1]),
                              latlong::DirectionFromElevationAzimuthDeg(10.0, -40.0), kWidth);
  skies.emplace_back("hazy sun 10", dir / "hazy.exr");
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const fit::FitOptions o = Defaults();
  for (const auto& [name, path] : skies) {
    const fit::Reference clean = fit::LoadReference(path, o);
    const double ceiling = fit::ModelCeiling(clean, DefaultStart(), o).lut_rel_rmse;
    for (int k = 0; k < 4; ++k) {
      render::Preset start = DefaultStart();
      for (auto* table : {&start.luts.rayleigh, &start.luts.mie, &start.luts.isotropic}) {
        const double scale = std::pow(10.0, -1.0 + 2.0 * u(rng));
        for (float& v : *table) v = static_cast<float>(v * scale);
      }
      start.haziness_g = 0.95 * u(rng);
      const double exposure = std::pow(10.0, -3.0 + 6.0 * u(rng));
      fit::Reference ref = clean;
      for (float& v : ref.radiance.pixels) v = static_cast<float>(v * exposure);
      const fit::FitResult r = fit::FitSky({ref}, start, o, *vulkan);
      const double err = r.references[0].errors.rel_rmse;
      SCOPED_TRACE(name + " start g " + std::to_string(start.haziness_g) + " exposure " + std::to_string(exposure));
      ASSERT_TRUE(std::isfinite(err));
      for (float v : r.preset.luts.mie) ASSERT_TRUE(std::isfinite(v));
      EXPECT_LE(err, 1.2 * ceiling + 1e-3);
    }
  }
}

}  // namespace
}  // namespace skycal
