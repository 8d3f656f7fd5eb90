// The unknown-shapes cloud lighting objective (cloudfit/include/skycal/cloudfit/cloud_stats.h): the
// statistics' identities, bad input, and the honest recovery test: a reference rendered
// with one noise seed and weather map, the fit rendering with different seeds, from a
// perturbed start. Tolerances from bench/results/cloud_stats_seed_pairs.md and (regime 2)
// bench/results/cloud-stats-gls/.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include <Eigen/Dense>

#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/cloudfit/cloud_stats.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

#include <ceres/problem.h>

#include "cloud_stats_term.h"
#include "skycal/cloudfit/cloud_stats_objective.h"

namespace skycal::cloudfit {
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
  o = {};
  o.noise_draws = 2;  // too few draws for an sd
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("noise_draws"), std::string::npos);
  o = {};
  o.noise_covariance = "shrunk";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("noise_covariance = 'shrunk' (expected diagonal or full)"), std::string::npos) << why;
  o = {};
  o.noise_shrinkage = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("noise_shrinkage"), std::string::npos) << why;
  o.noise_shrinkage = -1.0;  // estimated
  EXPECT_TRUE(o.IsValid(&why)) << why;
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
  // The test scene: sun 25 deg up at azimuth 30, renders of 64x32 (the benchmark's 128x64
  // costs ~4x as much per render).
  bench::CloudStatsSyntheticScene Scene(bench::CloudStatsSeeds ref, bench::CloudStatsSeeds model, CloudStatsOptions* o) {
    o->render_width = 64;
    o->render_height = 32;
    return bench::MakeCloudStatsScene(kRoot, ref, model, 25.0, 30.0, *o, *renderer, cache);
  }
};

TEST(CloudStats, UnknownFieldAndCloudlessReferenceAreRefused) {
  Fixture f;
  CloudStatsOptions o;
  auto scene = f.Scene({1, 11}, {1, 11}, &o);
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

// The FitTerm a caller plugs into FitSkyWithTerms: held parameters reported with their
// reasons, nothing added on coarse levels, one block of the free parameters with the
// objective's residuals on the finest.
TEST(CloudStats, TermAddsItsBlockOnTheFinestLevelAndReportsWhatItHolds) {
  Fixture f;
  CloudStatsOptions o;
  auto scene = f.Scene({1, 11}, {1, 11}, &o);
  const std::vector<CloudStatsReference> refs = {scene.reference};
  const CloudStatsScene model{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  auto term = MakeCloudStatsTerm(refs, model, *f.renderer, o);
  std::vector<fit::SkipNote> skipped;
  std::vector<fit::FitDecision> decisions;
  term->ReportSkips(&skipped, &decisions);
  bool g2 = false, g1 = false;
  for (const auto& n : skipped) {
    g2 |= n.block == "clouds.phase_g2" && n.reason.find("held: ") == 0;
    // Held by default: the shape noise cannot separate it (the measured spread is named).
    g1 |= n.block == "clouds.phase_g1" && n.reason.find("not separable") != std::string::npos;
  }
  bool extinction = false;
  for (const auto& n : skipped)
    extinction |= n.block == "clouds.extinction" && n.reason.find("not determined") != std::string::npos;
  EXPECT_TRUE(g2);
  EXPECT_TRUE(g1);
  EXPECT_TRUE(extinction);  // held by default since the regime-2 seed pairs (cloud_stats.h)
  EXPECT_EQ(skipped.size(), 15u);  // 16 lighting fields, 1 fitted (ambient_strength)
  fit::FitState state;
  fit::LevelContext level;
  ceres::Problem problem;
  EXPECT_EQ(term->AddTo(problem, state, level), 0);
  level.finest = true;
  const long long n = term->AddTo(problem, state, level);
  EXPECT_GT(n, 0);
  EXPECT_EQ(problem.NumParameterBlocks(), 1);
  EXPECT_EQ(problem.NumParameters(), 1);
  EXPECT_EQ(problem.NumResiduals(), n);
  EXPECT_EQ(term->result().params.extinction_per_m, scene.truth.extinction_per_m);
}

// Whitening by the shape noise (options.noise_draws): draws of identical shapes have no
// spread, so every statistic's sd is 0 and is floored, and each residual is then exactly
// (model - reference) / (floor sqrt(1 + 1/M)); draws of other weather maps spread (measured
// median sd 0.13 log radiance at 64x32, bench/results/cloud_stats_seed_pairs.md): the control
// that the identity is not vacuous.
TEST(CloudStats, WhiteningDividesEachResidualByItsShapeNoise) {
  Fixture f;
  CloudStatsOptions o;
  auto scene = f.Scene({1, 11}, {101, 211}, &o);
  const std::vector<CloudStatsReference> refs = {scene.reference};
  CloudStatsScene same{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  same.shape_draw_maps.assign(4, &scene.weather);  // draw d: the same map at wind offset 0
  const CloudStatsObjective obj(refs, same, *f.renderer, o);
  const std::vector<double> x = obj.InitialX();
  const std::vector<double> sd = obj.EstimateNoiseSd(x.data(), 4);
  int filled = 0;
  for (double v : sd) {
    if (v == 1e3 * o.noise_sd_floor) continue;  // a bin some draw leaves empty
    ++filled;
    EXPECT_LT(v, 1e-6);  // float statistics, double sums
  }
  EXPECT_GT(filled, 20);
  CloudStatsObjective whitened(refs, same, *f.renderer, o);
  whitened.SetNoiseSd(sd);
  std::vector<double> model(whitened.num_residuals()), r(whitened.num_residuals());
  ASSERT_TRUE(whitened.ModelStatistics(x.data(), model.data()));
  ASSERT_TRUE(whitened.Evaluate(x.data(), r.data()));
  const double pooled = std::sqrt(1.0 + 1.0 / o.model_renders);
  int checked = 0;
  for (int k = 0; k < whitened.num_residuals(); ++k) {
    if (!std::isfinite(model[k]) || sd[k] > 1.0) continue;
    EXPECT_NEAR(r[k], (model[k] - whitened.ReferenceStatistics()[k]) / (o.noise_sd_floor * pooled), 1e-9) << k;
    ++checked;
  }
  EXPECT_GT(checked, 20);
  // Control: other weather maps spread the statistics well above the floor.
  std::vector<clouds::WeatherMap> maps;
  for (int d = 0; d < 4; ++d) maps.push_back(bench::CloudStatsWeather(5000 + d, scene.truth.weather_extent_m));
  CloudStatsScene other = same;
  other.shape_draw_maps.clear();
  for (const auto& w : maps) other.shape_draw_maps.push_back(&w);
  const CloudStatsObjective spread(refs, other, *f.renderer, o);
  std::vector<double> sd2 = spread.EstimateNoiseSd(x.data(), 4), present;
  for (double v : sd2)
    if (v != 1e3 * o.noise_sd_floor) present.push_back(v);
  ASSERT_GT(present.size(), 5u);
  std::nth_element(present.begin(), present.begin() + present.size() / 2, present.end());
  EXPECT_GT(present[present.size() / 2], 2.0 * o.noise_sd_floor);
}

// The full GLS inside the objective: with a covariance set from draws (synthetic numbers
// here: no render needed for them), Evaluate's squared norm is dᵀ (Σ (1 + 1/M))^-1 d for
// d = model - reference, Σ recomputed here from the draws by hand (sample covariance, fixed
// λ, floored variances; a statistic one draw leaves empty: uncorrelated, variance
// (1e3 floor)²). Control: the diagonal whitening of the same d is a different number.
TEST(CloudStats, FullWhiteningIsTheGlsCostOfTheDraws) {
  Fixture f;
  CloudStatsOptions o;
  auto scene = f.Scene({1, 11}, {101, 211}, &o);
  const std::vector<CloudStatsReference> refs = {scene.reference};
  const CloudStatsScene model{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  CloudStatsObjective obj(refs, model, *f.renderer, o);
  const int n = obj.num_residuals();
  const std::vector<double> x = obj.InitialX();
  std::vector<double> stats(n);
  ASSERT_TRUE(obj.ModelStatistics(x.data(), stats.data()));
  // 12 draws: a common factor (correlated statistics) plus independent parts, scale 0.1.
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::vector<double>> draws(12, std::vector<double>(n));
  for (auto& d : draws) {
    const double common = g(rng);
    for (int k = 0; k < n; ++k) d[k] = 0.1 * (0.8 * common + 0.6 * g(rng)) * (1.0 + (k % 5));
  }
  const int absent = 3;
  draws[5][absent] = std::nan("");
  const double lambda = 0.3;
  EXPECT_EQ(obj.SetNoiseCovariance(draws, lambda), lambda);
  ASSERT_TRUE(obj.full_whitening());
  std::vector<double> r(n);
  ASSERT_TRUE(obj.Evaluate(x.data(), r.data()));
  Eigen::VectorXd d(n);
  for (int k = 0; k < n; ++k)
    d(k) = std::isnan(stats[k]) ? o.empty_bin_log_residual : stats[k] - obj.ReferenceStatistics()[k];
  Eigen::MatrixXd sigma = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      if (i == absent || j == absent) continue;
      double mi = 0.0, mj = 0.0, c = 0.0;
      for (const auto& v : draws) mi += v[i] / 12.0, mj += v[j] / 12.0;
      for (const auto& v : draws) c += (v[i] - mi) * (v[j] - mj) / 11.0;
      sigma(i, j) = i == j ? std::max(c, o.noise_sd_floor * o.noise_sd_floor) : (1.0 - lambda) * c;
    }
  sigma(absent, absent) = std::pow(1e3 * o.noise_sd_floor, 2);
  sigma *= 1.0 + 1.0 / o.model_renders;
  const double gls = d.dot(sigma.ldlt().solve(d));
  double norm2 = 0.0;
  for (double v : r) norm2 += v * v;
  EXPECT_NEAR(norm2, gls, 1e-8 * gls);
  // Control: the diagonal whitening of the same statistics.
  CloudStatsObjective diag(refs, model, *f.renderer, o);
  diag.SetNoiseSd(diag.NoiseSd(draws));
  ASSERT_TRUE(diag.Evaluate(x.data(), r.data()));
  double diag2 = 0.0;
  for (double v : r) diag2 += v * v;
  std::cout << "[cloud stats] GLS cost " << gls << ", diagonal " << diag2 << "\n";
  EXPECT_GT(std::abs(diag2 - gls), 0.1 * gls);
}

// The start of every recovery: the truth x (extinction 1.3, g1 0.7, powder 0.7, ambient
// 1.3), as in the fit-cloud-stats suite.
clouds::CloudParams Perturbed(const clouds::CloudParams& truth) {
  clouds::CloudParams start = truth;
  start.extinction_per_m *= 1.3;
  start.phase_g1 *= 0.7;
  start.powder_strength *= 0.7;
  start.ambient_strength *= 1.3;
  return start;
}

struct Errors {
  double extinction, g1, powder, ambient;
};
Errors RelErrors(const clouds::CloudParams& p, const clouds::CloudParams& t) {
  auto rel = [](double v, double truth) { return std::abs(v - truth) / truth; };
  const Errors e{rel(p.extinction_per_m, t.extinction_per_m), rel(p.phase_g1, t.phase_g1),
                 rel(p.powder_strength, t.powder_strength), rel(p.ambient_strength, t.ambient_strength)};
  std::cout << "[cloud stats] rel errors: extinction " << e.extinction << " g1 " << e.g1 << " powder " << e.powder
            << " ambient " << e.ambient << "\n";
  return e;
}

// Known shapes (the model renders the reference's own seeds, once): the statistics are then
// identical at the truth, and the fit must land on it; the start is 30% off, so a fit that
// did not move fails.
TEST(CloudStats, KnownShapesControlRecoversTheTruth) {
  Fixture f;
  CloudStatsOptions o;
  // With known shapes all four are recovered (the default holds g1 and powder: unknown shapes).
  o.fitted = {"extinction", "phase_g1", "powder_strength", "ambient_strength"};
  o.model_renders = 1;
  o.max_iterations = 6;  // CI time (the sanitizer build is ~10x slower); measured to suffice below
  auto scene = f.Scene({1, 11}, {1, 11}, &o);
  const CloudStatsScene model{&scene.preset, Perturbed(scene.truth), &scene.noise, &scene.weather};
  const CloudStatsResult r = FitCloudStats({scene.reference}, model, *f.renderer, o);
  std::cout << "[cloud stats] " << r.termination << ", " << r.renders << " renders, " << r.time_s << " s\n";
  const Errors e = RelErrors(r.params, scene.truth);
  // 2%: the statistics are identical at the truth; measured at 64x32 after 6 iterations:
  // extinction 4e-4, g1 0.0104, ambient 0.0019 (converged: 8e-6, 0.0096, 0.0013; the bench's
  // control at 128x64: all < 0.05%). Powder 15%: at 64x32 it is the least determined
  // parameter (few thin-edge pixels; the cost is 9e-5 from 0.08 with powder 10.1% off, and
  // stays at 9.9% when converged); at 128x64 the control recovers it exactly.
  EXPECT_LT(e.extinction, 0.02);
  EXPECT_LT(e.g1, 0.02);
  EXPECT_LT(e.powder, 0.15);
  EXPECT_LT(e.ambient, 0.02);
  // Held parameters say why.
  int held = 0;
  for (const auto& q : r.parameters)
    if (q.held) {
      ++held;
      EXPECT_FALSE(q.why_held.empty()) << q.name;
    }
  EXPECT_EQ(held, static_cast<int>(r.parameters.size()) - 4);
}

// Unknown shapes (other noise and weather seeds): the objective at the truth is below the
// objective at the perturbed start (the statistics point toward the truth; measured 0.377
// vs 0.486 when written; 0.434 vs 0.443 now, the same on main before the full GLS: a thin
// margin). Not a recovery bound: with the first design's weights the fit lands 13-100% off
// over seed pairs (bench/results/cloud_stats_seed_pairs.md);
// the bound is Regime2UnknownShapesRecoverTheAmbient's, with the whitening.
TEST(CloudStats, UnknownShapesPointTowardTheTruth) {
  Fixture f;
  CloudStatsOptions o;
  o.max_iterations = 0;
  auto scene = f.Scene({1, 11}, {101, 211}, &o);
  const CloudStatsScene at_truth{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  const CloudStatsScene at_start{&scene.preset, Perturbed(scene.truth), &scene.noise, &scene.weather};
  const double cost_truth = FitCloudStats({scene.reference}, at_truth, *f.renderer, o).initial_cost;
  const double cost_start = FitCloudStats({scene.reference}, at_start, *f.renderer, o).initial_cost;
  std::cout << "[cloud stats] cost at the truth " << cost_truth << ", at the start " << cost_start << "\n";
  EXPECT_LT(cost_truth, cost_start);
}

// Regime 2 (docs/cloud-fitting.md): ONE unknown-shapes seed pair — the reference rendered with noise /
// weather seeds 2/12, the model with 102/212 (and weather maps 1212, 2212, 3212) — the
// default fitted set (ambient_strength) from 30% off, whitened by the diagonal shape noise
// of 24 draws (weather maps 5000-5023 x noise textures 7001-7006), 64x32, 4 model renders, at
// most 8 iterations: exactly the case `diag-ambient` of
//   build/skycal bench --suite fit-cloud-stats-gls --out DIR   (bench/results/cloud-stats-gls/)
// (pair 1 there: +5.7%). Its 5 pairs spread 3.4-28.7% (median 7.4%): the tolerance is the
// worst x 1.5 = 43%.
constexpr double kRegime2AmbientTolerance = 1.5 * 0.287;

// The pair's scene, built once for the fit and its control (each noise texture is 34 MB:
// ~0.4 s to load and check).
struct Regime2Pair {
  CloudStatsOptions o;
  bench::CloudStatsSyntheticScene scene;
  std::vector<clouds::WeatherMap> ensemble, maps;
  std::vector<clouds::CloudNoise> textures;
  explicit Regime2Pair(Fixture& f) {
    o.model_renders = 4;
    o.noise_draws = 24;
    o.noise_covariance = "diagonal";
    scene = f.Scene({2, 12}, {102, 212}, &o);
    ensemble.push_back(scene.weather);
    for (int e = 1; e < 4; ++e) ensemble.push_back(bench::CloudStatsWeather(212 + 1000 * e, scene.truth.weather_extent_m));
    for (int d = 0; d < o.noise_draws; ++d) maps.push_back(bench::CloudStatsWeather(5000 + d, scene.truth.weather_extent_m));
    for (uint64_t seed = 7001; seed <= 7006; ++seed) textures.push_back(clouds::LoadOrGenerateCloudNoise(seed, f.cache));
  }
  // |fitted ambient / truth - 1| from the truth x ambient_start.
  double AmbientError(Fixture& f, double ambient_start, int max_iterations, CloudStatsResult* result) const {
    CloudStatsOptions run = o;
    run.max_iterations = max_iterations;
    // The control (0 iterations) does not move, so it needs no whitening: its 24 draws are saved.
    if (max_iterations == 0) run.noise_draws = 0;
    clouds::CloudParams start = scene.truth;
    start.ambient_strength *= ambient_start;
    CloudStatsScene model{&scene.preset, start, &scene.noise, &scene.weather};
    for (const auto& w : ensemble) model.weather_ensemble.push_back(&w);
    for (const auto& w : maps) model.shape_draw_maps.push_back(&w);
    for (const auto& t : textures) model.shape_draw_noises.push_back(&t);
    *result = FitCloudStats({scene.reference}, model, *f.renderer, run);
    std::cout << "[cloud stats] regime 2: " << result->termination << ", " << result->renders << " renders, "
              << result->time_s << " s\n";
    return std::abs(result->params.ambient_strength / scene.truth.ambient_strength - 1.0);
  }
};

TEST(CloudStats, Regime2UnknownShapesRecoverTheAmbient) {
  ASSERT_EQ(CloudStatsOptions{}.fitted, std::vector<std::string>{"ambient_strength"});  // the default the bench measured
  Fixture f;
  const Regime2Pair pair(f);
  CloudStatsResult fit;
  const double ambient = pair.AmbientError(f, 1.3, 8, &fit);
  std::cout << "[cloud stats] regime 2: ambient " << ambient << "\n";
  EXPECT_EQ(fit.noise_covariance, "diagonal");
  EXPECT_EQ(fit.noise_draws, 24);
  EXPECT_LT(ambient, kRegime2AmbientTolerance);
  EXPECT_GT(fit.iterations, 1);  // it moved (the start is 30% off)
  // Control: a start far outside the tolerance (2x) that the fit is not allowed to leave
  // (0 iterations) fails the bound. (Tried first: the extinction held 40% low, a mis-specified
  // lighting left unfitted: ambient lands 23% off, inside the 43%: the bound cannot see that.)
  CloudStatsResult stuck;
  const double ambient_stuck = pair.AmbientError(f, 2.0, 0, &stuck);
  std::cout << "[cloud stats] regime 2 control: ambient " << ambient_stuck << "\n";
  EXPECT_GT(ambient_stuck, kRegime2AmbientTolerance);
}

// A bin the reference fills and the render leaves empty: no residual by default (the old
// behaviour), options.empty_bin_log_residual x the bin's weight when set. The model's
// extinction near 0: the render's clouds vanish and its bins empty.
TEST(CloudStats, EmptyModelBinsAddTheirResidualWhenAsked) {
  Fixture f;
  CloudStatsOptions o;
  o.fitted = {"extinction"};
  o.opacity_share_weight = 0.0;
  auto scene = f.Scene({1, 11}, {1, 11}, &o);
  clouds::CloudParams vanished = scene.truth;
  vanished.extinction_per_m = 1e-6;  // opacity far below the thin class's 0.1
  const CloudStatsScene model{&scene.preset, vanished, &scene.noise, &scene.weather};
  std::vector<std::vector<double>> res;
  const std::vector<CloudStatsReference> refs = {scene.reference};  // the objective keeps a reference
  for (const double penalty : {0.0, 2.0}) {
    o.empty_bin_log_residual = penalty;
    CloudStatsObjective obj(refs, model, *f.renderer, o);
    const std::vector<double> x = obj.InitialX();
    res.emplace_back(obj.num_residuals());
    ASSERT_TRUE(obj.Evaluate(x.data(), res.back().data()));
  }
  // Residuals of empty bins: 0 without the option (the control), 2 x sqrt(bin / total) with
  // it; bins the render still fills (the cirrus sheet) are the same in both.
  int empty = 0;
  double weight_sq = 0.0;
  for (size_t i = 0; i < res[0].size(); ++i) {
    if (res[0][i] == res[1][i]) continue;
    EXPECT_EQ(res[0][i], 0.0) << i;
    EXPECT_GT(res[1][i], 0.0) << i;
    ++empty;
    weight_sq += (res[1][i] / 2.0) * (res[1][i] / 2.0);
  }
  EXPECT_GT(empty, 9);              // at least one bin's 3 channels x 3 quantiles
  EXPECT_LE(weight_sq, 9.0 + 1e-9);  // the weights' squares sum to <= 1 per channel x quantile
  o.empty_bin_log_residual = -1.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("empty_bin_log_residual"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal::cloudfit
