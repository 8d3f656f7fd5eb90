// The unknown-shapes cloud lighting objective (fit/include/skycal/fit/cloud_stats.h): the
// statistics' identities, bad input, and the honest recovery test: a reference rendered
// with one noise seed and weather map, the fit rendering with different seeds, from a
// perturbed start. Tolerances from bench/results/cloud_stats_seed_pairs.md.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/cloud_stats.h"

namespace skycal::fit {
namespace {

const std::string kRoot = SKYCAL_SOURCE_DIR;

TEST(CloudStats, QuantilesOfKnownPopulations) {
  CloudStatsOptions o;
  const int w = 64, h = 32;
  ImageRGB img(w, h);
  std::vector<float> opacity(static_cast<size_t>(w) * h, 0.0f);
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(60.0, 0.0);
  double omega = 0.0;
  // Rows 4..9 (elevation ~ 33..57 deg... each row its own), columns 0..31 at radiance 2,
  // 32..63 at radiance 8; opacity 1 (thick class weight 1). One elevation bin may hold
  // both halves; its median must sit midway in log (equal weights: the interpolated CDF).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float v = x < 32 ? 2.0f : 8.0f;
      img.pixels[3 * i] = img.pixels[3 * i + 1] = img.pixels[3 * i + 2] = v;
      opacity[i] = 1.0f;
    }
  const CloudStatistics s = ComputeCloudStatistics(img, opacity, {}, sun, o);
  // Total thick weight = the solid angle of the rows within the elevation edges [2, 90].
  for (int y = 0; y < h; ++y) {
    const double el = latlong::Latitude(y, h) * 180.0 / M_PI;
    if (el < 2.0) continue;
    for (int x = 0; x < w; ++x) omega += latlong::PixelSolidAngle(x, y, w, h);
  }
  double total = 0.0;
  for (double wt : s.weight) total += wt;
  EXPECT_NEAR(total, omega, 1e-9 * omega);
  // Every quantile lies within [ln 2, ln 8]; every bin holding only one value has it at
  // every quantile; the uniform opacity puts nothing in the thin class.
  int mixed = 0;
  const int nq = static_cast<int>(o.quantiles.size());
  for (int sb = 0; sb < s.sun_bins; ++sb)
    for (int eb = 0; eb < s.elevation_bins; ++eb) {
      EXPECT_EQ(s.weight[s.Bin(sb, eb, 0)], 0.0);
      const int bin = s.Bin(sb, eb, 1);
      if (s.weight[bin] == 0.0) continue;
      const double lo = s.log_quantile[(static_cast<size_t>(bin) * 3) * nq];
      const double hi = s.log_quantile[(static_cast<size_t>(bin) * 3) * nq + nq - 1];
      EXPECT_GE(lo, std::log(2.0) - 1e-6);  // float logs
      EXPECT_LE(hi, std::log(8.0) + 1e-6);
      mixed += hi - lo > 1.0;
    }
  EXPECT_GT(mixed, 0);
}

TEST(CloudStats, MedianOfTwoEqualHalvesIsTheirLogMidpoint) {
  CloudStatsOptions o;
  o.sun_angle_edges_deg = {0.0, 180.0};
  o.elevation_edges_deg = {-90.0, 90.0};
  o.quantiles = {0.5};
  // Two pixels of equal solid angle (the same row), radiance 1 and e^2.
  const int w = 16, h = 8;
  ImageRGB img(w, h);
  std::vector<float> opacity(static_cast<size_t>(w) * h, 0.0f);
  for (int x : {3, 7}) {
    const size_t i = static_cast<size_t>(2) * w + x;
    const float v = x == 3 ? 1.0f : static_cast<float>(std::exp(2.0));
    img.pixels[3 * i] = img.pixels[3 * i + 1] = img.pixels[3 * i + 2] = v;
    opacity[i] = 1.0f;
  }
  const CloudStatistics s = ComputeCloudStatistics(img, opacity, {}, {0.0, 1.0, 0.0}, o);
  EXPECT_NEAR(s.log_quantile[static_cast<size_t>(s.Bin(0, 0, 1)) * 3], 1.0, 1e-6);
  // A sky mask removes a pixel: the median is then that of the other alone.
  std::vector<float> sky(static_cast<size_t>(w) * h, 1.0f);
  sky[static_cast<size_t>(2) * w + 7] = 0.0f;
  const CloudStatistics masked = ComputeCloudStatistics(img, opacity, sky, {0.0, 1.0, 0.0}, o);
  EXPECT_NEAR(masked.log_quantile[static_cast<size_t>(masked.Bin(0, 0, 1)) * 3], 0.0, 1e-6);
}

TEST(CloudStats, BadOptionsAndReferencesAreNamed) {
  std::string why;
  CloudStatsOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.quantiles = {0.5, 1.0};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("quantiles"), std::string::npos);
  o = {};
  o.render_width = 2;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("render size"), std::string::npos);
  EXPECT_THROW(ComputeCloudStatistics(ImageRGB(8, 4), std::vector<float>(3), {}, {0, 1, 0}, {}), Error);
}

struct Fixture {
  std::unique_ptr<clouds::CloudRenderer> renderer;
  std::string cache = (std::filesystem::temp_directory_path() / "skycal-cloud-stats-cache").string();
  Fixture() {
    try {
      renderer = clouds::CreateVulkanCloudRenderer(false);
    } catch (const Error&) {
      renderer = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2);
    }
  }
};

TEST(CloudStats, UnknownFieldAndCloudlessReferenceAreRefused) {
  Fixture f;
  CloudStatsOptions o;
  o.render_width = 64;
  o.render_height = 32;
  auto scene = bench::MakeCloudStatsScene(kRoot, {1, 11}, {2, 12}, 25.0, 30.0, o, *f.renderer, f.cache);
  const CloudStatsScene model{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  CloudStatsOptions bad = o;
  bad.fitted = {"extinction", "phase_gg"};
  try {
    FitCloudStats({scene.reference}, model, *f.renderer, bad);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("clouds.phase_gg"), std::string::npos) << e.what();
  }
  CloudStatsReference clear = scene.reference;
  std::fill(clear.opacity.begin(), clear.opacity.end(), 0.0f);
  try {
    FitCloudStats({clear}, model, *f.renderer, o);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no cloud pixels"), std::string::npos) << e.what();
  }
}

TEST(CloudStats, RecoversTheLightingWithOtherShapes) {
  Fixture f;
  CloudStatsOptions o;
  o.render_width = 128;
  o.render_height = 64;
  o.max_iterations = 15;
  auto scene = bench::MakeCloudStatsScene(kRoot, {1, 11}, {101, 211}, 25.0, 30.0, o, *f.renderer, f.cache);
  // Start: the truth perturbed as in the benchmark (clamped into bounds).
  clouds::CloudParams start = scene.truth;
  start.extinction_per_m *= 1.3;
  start.phase_g1 *= 0.7;
  start.phase_g2 *= 0.8;
  start.phase_blend *= 1.3;
  start.powder_strength *= 0.7;
  start.ambient_strength *= 1.3;
  const CloudStatsScene model{&scene.preset, start, &scene.noise, &scene.weather};
  const CloudStatsResult r = FitCloudStats({scene.reference}, model, *f.renderer, o);
  std::cout << "[cloud stats] " << r.termination << "\n";
  const auto& t = scene.truth;
  const auto& p = r.params;
  auto rel = [](double v, double truth) { return std::abs(v - truth) / truth; };
  std::cout << "[cloud stats] extinction " << rel(p.extinction_per_m, t.extinction_per_m) << " g1 "
            << rel(p.phase_g1, t.phase_g1) << " g2 " << rel(p.phase_g2, t.phase_g2) << " blend "
            << rel(p.phase_blend, t.phase_blend) << " powder " << rel(p.powder_strength, t.powder_strength)
            << " ambient " << rel(p.ambient_strength, t.ambient_strength) << "; " << r.renders << " renders, "
            << r.time_s << " s\n";
  EXPECT_LT(r.final_cost, 0.5 * r.initial_cost);
  EXPECT_LT(rel(p.phase_g1, t.phase_g1), 1.0);
  // Held parameters say why.
  int held = 0;
  for (const auto& q : r.parameters)
    if (q.held) {
      ++held;
      EXPECT_FALSE(q.why_held.empty()) << q.name;
    }
  EXPECT_EQ(held, static_cast<int>(r.parameters.size()) - 6);
}

}  // namespace
}  // namespace skycal::fit
