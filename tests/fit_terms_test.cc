// The fit as pluggable terms (fit/src/fit_term.h, fit/src/level_solve.h) and its skip
// decisions (fit.json `decisions`, fit/src/fit_decisions.h):
//  - the Ceres path through the terms gives the LUT the fit gave before the split (the
//    digests below were taken from the commit before it, 06389f8, on the same synthetic
//    sky: LUT EXRs byte-identical, checked with cmp);
//  - a term plugs in beside the built-in ones and steers the fit;
//  - fit.json lists the decisions with finite, non-negative savings and their basis;
//  - ffxv-iso holds the overcast L_z (not separable from the isotropic table) and says so.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "fit_decisions.h"
#include "fit_term.h"
#include "pyramid.h"
#include "run_binary.h"
#include "sky_fit_terms.h"
#include "skycal/core/json_file.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "test_util.h"
#include "unseen_profile_term.h"

namespace skycal {
namespace {

using testing::ScratchDir;

testing::ProcessResult Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

const std::string kDefaultPreset = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json";

// The synthetic sky: the default preset at sun 25 deg, azimuth 40 deg, 256x128, CPU.
std::string RenderSky(const ScratchDir& dir) {
  const std::string path = dir / "sky.exr";
  const auto r = Skycal("render --sun-elevation 25 --sun-azimuth 40 --size 256x128 --backend cpu --out " + path);
  EXPECT_EQ(r.rc, 0) << r.err;
  return path;
}

// Per table: the sum and the sum of squares of its entries (doubles of the float LUT).
struct Digest {
  double sum = 0.0, sum_sq = 0.0;
};
Digest DigestOf(const std::vector<float>& table) {
  Digest d;
  for (float v : table) {
    d.sum += v;
    d.sum_sq += static_cast<double>(v) * v;
  }
  return d;
}

void ExpectDigest(const std::vector<float>& table, double sum, double sum_sq, const std::string& what) {
  const Digest d = DigestOf(table);
  EXPECT_NEAR(d.sum / sum, 1.0, 1e-12) << what;
  EXPECT_NEAR(d.sum_sq / sum_sq, 1.0, 1e-12) << what;
}

TEST(FitTerms, CeresPathThroughTermsGivesTheLutOfBefore) {
  ScratchDir dir("fit-terms-same");
  const std::string sky = RenderSky(dir);
  {
    // ffxv-iso, the linear start then the Ceres polish (sky rows + LUT priors + probe term).
    const auto r = Skycal("fit --quiet --reference " + sky + " --backend cpu --polish --out " + (dir / "polish"));
    ASSERT_EQ(r.rc, 0) << r.err;
    const render::Preset p = render::LoadPreset(dir / "polish/preset.json");
    const nlohmann::json j = ReadJsonFile(dir / "polish/fit.json");
    ASSERT_EQ(j["levels"].size(), 1u);
    EXPECT_EQ(j["levels"][0]["iterations"].get<int>(), 16);
    ExpectDigest(p.luts.rayleigh, 105259095.55361749, 6009495313564.7607, "polish rayleigh");
    // Re-taken when LinearSky summed a row's normal matrix by feature moments (docs/fitting.md,
    // "A day's linear start"): the same sums in another order moved the Mie table by 2e-10 and
    // 7e-10 relative (the other tables and g unchanged at 1e-12).
    ExpectDigest(p.luts.mie, 9630228.150845457, 102797095794.87816, "polish mie");
    ExpectDigest(p.luts.isotropic, 2729036.7442824771, 2178182921.4094958, "polish isotropic");
    EXPECT_NEAR(p.haziness_g / 0.7990323238413235, 1.0, 1e-12);
  }
  {
    // ffxv, the old coarse-to-fine path: three levels from the default start.
    const auto r = Skycal("fit --quiet --reference " + sky + " --model ffxv --backend cpu --no-linear-start --out " +
                          (dir / "old"));
    ASSERT_EQ(r.rc, 0) << r.err;
    const render::Preset p = render::LoadPreset(dir / "old/preset.json");
    const nlohmann::json j = ReadJsonFile(dir / "old/fit.json");
    ASSERT_EQ(j["levels"].size(), 3u);
    ExpectDigest(p.luts.rayleigh, 105208484.55801202, 6001278484294.5264, "old rayleigh");
    ExpectDigest(p.luts.mie, 9624122.1136750467, 102777603402.67268, "old mie");
    EXPECT_NEAR(p.haziness_g / 0.80000000374502855, 1.0, 1e-12);
  }
}

// A term from outside the fit: pulls g toward a target with a weight far above the sky's
// (whose residual weights sum to 1 per channel), and reports a skip of its own.
class PullHaziness final : public fit::FitTerm {
 public:
  explicit PullHaziness(double target) : target_(target) {}
  std::string name() const override { return "test: pull g"; }
  long long AddTo(ceres::Problem& problem, fit::FitState& state, const fit::LevelContext& level) override {
    ++levels_;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Residual, 1, 1>(new Residual{target_}), nullptr,
                             &state.g);
    EXPECT_NE(level.levels, nullptr);
    return 1;
  }
  void ReportSkips(std::vector<fit::SkipNote>* skipped, std::vector<fit::FitDecision>*) const override {
    skipped->push_back({"test block", "plugged in"});
  }
  int levels() const { return levels_; }

 private:
  struct Residual {
    double target;
    template <typename T>
    bool operator()(const T* g, T* r) const {
      r[0] = T(100.0) * (g[0] - T(target));
      return true;
    }
  };
  double target_;
  int levels_ = 0;
};

TEST(FitTerms, ExtraTermPlugsInBesideTheSkyRows) {
  ScratchDir dir("fit-terms-plug");
  fit::FitOptions o;
  o.backend = render::Backend::kCpu;
  o.verbose = false;
  const fit::Reference ref = fit::LoadReference(RenderSky(dir), o);
  auto renderer = render::CreateRenderer(render::Backend::kCpu);
  const render::Preset start = render::LoadPreset(kDefaultPreset);
  PullHaziness pull(0.5);
  const fit::FitResult r = fit::FitSkyWithTerms({ref}, start, o, *renderer, {}, {&pull});
  EXPECT_EQ(pull.levels(), 1);  // the linear start, then the polish at the finest level (forced by the term)
  ASSERT_EQ(r.levels.size(), 1u);
  EXPECT_NEAR(r.preset.haziness_g, 0.5, 2e-3);
  const fit::FitResult plain = fit::FitSky({ref}, start, o, *renderer);
  EXPECT_NEAR(plain.preset.haziness_g, start.haziness_g, 2e-3);  // the sky's own g (the default's, 0.8)
  bool noted = false;
  for (const auto& s : r.skipped) noted = noted || (s.block == "test block" && s.reason == "plugged in");
  EXPECT_TRUE(noted);
}

TEST(FitTerms, DecisionsOnAClearSkySayWhatTheySaved) {
  ScratchDir dir("fit-terms-decisions");
  const std::string sky = RenderSky(dir);
  const auto r = Skycal("fit --quiet --reference " + sky + " --backend cpu --out " + (dir / "fit"));
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json j = ReadJsonFile(dir / "fit/fit.json");
  // The keys fit.json always had.
  for (const char* key : {"levels", "skipped", "linear_start", "unobserved_lut_rows", "probe", "iterations"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_TRUE(j["levels"].empty());  // the polish was skipped
  EXPECT_TRUE(j["linear_start"].contains("render_check"));
  ASSERT_TRUE(j["decisions"].is_array());
  std::map<std::string, nlohmann::json> by_what;
  for (const auto& d : j["decisions"]) {
    const double saved = d["saved_ms"].get<double>();
    EXPECT_TRUE(std::isfinite(saved) && saved >= 0.0) << d;
    const std::string basis = d["saved_ms_basis"].get<std::string>();
    EXPECT_TRUE(basis.rfind("measured", 0) == 0 || basis.rfind("estimated", 0) == 0 || basis.rfind("none", 0) == 0)
        << basis;
    EXPECT_FALSE(d["why"].get<std::string>().empty());
    by_what[d["what"].get<std::string>()] = d;
  }
  // 256x128: the lower half of the rows is ground, 128 x 256 / 2 pixels.
  ASSERT_EQ(by_what.count("16384 pixels below the horizon not evaluated"), 1u) << j["decisions"];
  EXPECT_GT(by_what["16384 pixels below the horizon not evaluated"]["saved_ms"].get<double>(), 0.0);
  ASSERT_EQ(by_what.count("Ceres polish skipped"), 1u) << j["decisions"];
  EXPECT_GT(by_what["Ceres polish skipped"]["saved_ms"].get<double>(), 0.0);
  ASSERT_EQ(by_what.count("coarse pyramid levels (64, 128 wide) not solved"), 1u) << j["decisions"];
  ASSERT_EQ(by_what.count("35 unobserved LUT rows held"), 1u) << j["decisions"];
  EXPECT_EQ(by_what["35 unobserved LUT rows held"]["rel_rmse_change"].get<double>(), 0.0);
  ASSERT_EQ(by_what.count("probe blocks of 1 of 1 references not built"), 1u) << j["decisions"];
  ASSERT_EQ(by_what.count("overcast term not fitted"), 1u) << j["decisions"];
}

TEST(FitTerms, OvercastHeldInFfxvIsoAndFittedInFfxv) {
  ScratchDir dir("fit-terms-overcast");
  const std::string sky = RenderSky(dir);
  render::Preset start = render::LoadPreset(kDefaultPreset);
  start.overcast_weight = 0.2;
  start.name = "overcast_start";
  render::SavePreset(start, dir / "overcast_start.json");
  auto fit = [&](const std::string& model) {
    const auto r = Skycal("fit --quiet --reference " + sky + " --init " + (dir / "overcast_start.json") +
                          " --model " + model + " --backend cpu --out " + (dir / model));
    EXPECT_EQ(r.rc, 0) << r.err;
    return ReadJsonFile(dir / (model + "/fit.json"));
  };
  auto has_decision = [](const nlohmann::json& j, const std::string& what) {
    for (const auto& d : j["decisions"]) {
      if (d["what"] == what) return d["saved_ms"].get<double>() >= 0.0;
    }
    return false;
  };
  const std::string held = "overcast zenith luminance L_z held (model ffxv-iso)";
  const nlohmann::json iso = fit("ffxv-iso");
  EXPECT_TRUE(has_decision(iso, held)) << iso["decisions"];
  bool skipped_note = false;
  for (const auto& s : iso["skipped"]) {
    skipped_note = skipped_note || (s["block"] == "overcast_zenith_luminance" &&
                                    s["reason"].get<std::string>().find("not separable") != std::string::npos);
  }
  EXPECT_TRUE(skipped_note) << iso["skipped"];
  // Folded into the isotropic table: L_z held at 1e-6 of the start's, and the sky fitted as
  // well as without an overcast term (held at the start's 4000 cd/m^2 instead, the
  // non-negative table cannot take back a term brighter than the sky: 25-327% rel RMSE on
  // the benchmark's skies, bench/results/fit_decisions.md).
  EXPECT_NEAR(render::LoadPreset(dir / "ffxv-iso/preset.json").overcast_zenith_cd_m2 / start.overcast_zenith_cd_m2,
              1e-6, 1e-12);
  EXPECT_LT(iso["references"][0]["rel_rmse"].get<double>(), 1e-3);
  const nlohmann::json two = fit("ffxv");
  EXPECT_FALSE(has_decision(two, held));
  for (const auto& s : two["skipped"]) EXPECT_NE(s["block"], "overcast_zenith_luminance") << s;
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

// Skip decisions (docs/fitting.md): the coarse levels' saving is estimated from this run when this
// run solved the finest level (--polish): that level's measured time x the skipped levels'
// share of its samples; without the polish the bench estimate (the fit-decisions suite).
TEST(FitTerms, CoarseLevelsSavedIsEstimatedFromThisRunWhenThePolishRan) {
  // The arithmetic: 64 and 128 of 256 wide hold 1/16 + 1/4 of its samples.
  fit::FitDecision bench;
  bench.what = "coarse";
  bench.saved_ms = 689.0;
  const fit::FitDecision d = fit::SkippedLevelsFromThisRun(bench, {64, 128}, 256, 1.0);
  EXPECT_NEAR(d.saved_ms, 312.5, 1e-9);
  EXPECT_EQ(d.saved_ms_basis.rfind("estimated from this run", 0), 0u) << d.saved_ms_basis;
  EXPECT_NE(d.saved_ms_basis.find("689 ms"), std::string::npos) << d.saved_ms_basis;  // the cross-check

  ScratchDir dir("fit-terms-coarse-saved");
  const auto r = Skycal("render --sun-elevation 25 --sun-azimuth 40 --size 128x64 --backend cpu --out " +
                        (dir / "sky.exr"));
  ASSERT_EQ(r.rc, 0) << r.err;
  fit::FitOptions o;
  o.verbose = false;
  o.backend = render::Backend::kCpu;
  const fit::Reference ref = fit::LoadReference(dir / "sky.exr", o);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  auto coarse = [](const fit::FitResult& result) {
    for (const fit::FitDecision& d : result.decisions) {
      if (d.what.rfind("coarse pyramid levels", 0) == 0) return d;
    }
    ADD_FAILURE() << "no coarse-level decision";
    return fit::FitDecision{};
  };
  const fit::FitResult plain = fit::FitSky({ref}, render::LoadPreset(kDefaultPreset), o, *cpu);
  EXPECT_TRUE(plain.levels.empty());
  EXPECT_EQ(coarse(plain).saved_ms_basis.rfind("estimated from the fit-decisions bench suite", 0), 0u) << coarse(plain).saved_ms_basis;
  o.polish = true;
  const fit::FitResult polished = fit::FitSky({ref}, render::LoadPreset(kDefaultPreset), o, *cpu);
  ASSERT_EQ(polished.levels.size(), 1u);
  const fit::FitDecision c = coarse(polished);
  EXPECT_EQ(c.saved_ms_basis.rfind("estimated from this run", 0), 0u) << c.saved_ms_basis;
  // 128 wide: the automatic pyramid's coarser levels, each (w / 128)^2 of the samples.
  double share = 0.0;
  const std::vector<int> widths = fit::AutomaticPyramid(128);
  for (size_t i = 0; i + 1 < widths.size(); ++i) share += (widths[i] / 128.0) * (widths[i] / 128.0);
  ASSERT_GT(share, 0.0);
  EXPECT_NEAR(c.saved_ms, 1e3 * polished.levels.back().time_s * share, 1e-9 * c.saved_ms);
}

// The polish's unseen-profile residuals (unseen_profile_term.h) in numbers: zero at the start,
// blind to a level common to the three columns (the data set the level), and the second and
// first differences of the change when one column moves.
TEST(UnseenProfileCost, ZeroAtTheStartBlindToALevelAndTheDifferencesOfOneColumn) {
  double p[3][2] = {{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};  // two LUT parameters per column (log)
  fit::UnseenProfileResidual r;
  const double a[3][2] = {{2.0, 0.5}, {1.5, 3.0}, {0.25, 4.0}};
  for (int i = 0; i < 3; ++i) {
    for (int n = 0; n < 2; ++n) r.nodes[i].push_back({&p[i][n], a[i][n]});
    r.log_l0[i] = std::log(a[i][0] + a[i][1]);
  }
  r.second = {0.1, -0.2, 0.1};
  r.first = {0.0, -0.3, 0.3};
  std::unique_ptr<ceres::CostFunction> cost(fit::MakeUnseenProfileCost(r));
  ASSERT_EQ(cost->parameter_block_sizes().size(), 6u);
  ASSERT_EQ(cost->num_residuals(), 2);
  const double* blocks[6] = {&p[0][0], &p[0][1], &p[1][0], &p[1][1], &p[2][0], &p[2][1]};
  double res[2];
  auto evaluate = [&] { ASSERT_TRUE(cost->Evaluate(blocks, res, nullptr)); };
  evaluate();
  EXPECT_NEAR(res[0], 0.0, 1e-15);
  EXPECT_NEAR(res[1], 0.0, 1e-15);
  for (auto& column : p) column[0] = column[1] = 0.7;  // every column x e^0.7: a level
  evaluate();
  EXPECT_NEAR(res[0], 0.0, 1e-12);
  EXPECT_NEAR(res[1], 0.0, 1e-12);
  for (auto& column : p) column[0] = column[1] = 0.0;
  p[1][0] = p[1][1] = 0.4;  // the middle column x e^0.4
  evaluate();
  EXPECT_NEAR(res[0], -0.2 * 0.4, 1e-12);
  EXPECT_NEAR(res[1], -0.3 * 0.4, 1e-12);
  // One parameter's derivative is its share of its column's L times that column's weights.
  p[1][0] = p[1][1] = 0.0;
  double j[6][2];
  double* jacobians[6] = {j[0], j[1], j[2], j[3], j[4], j[5]};
  ASSERT_TRUE(cost->Evaluate(blocks, res, jacobians));
  EXPECT_NEAR(j[2][0], -0.2 * 1.5 / 4.5, 1e-12);
  EXPECT_NEAR(j[2][1], -0.3 * 1.5 / 4.5, 1e-12);
  EXPECT_NEAR(j[5][0], 0.1 * 4.0 / 4.25, 1e-12);
  EXPECT_NEAR(j[5][1], 0.3 * 4.0 / 4.25, 1e-12);
}

}  // namespace
}  // namespace skycal
