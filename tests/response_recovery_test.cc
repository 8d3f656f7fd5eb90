// Camera-response recovery on tone curves the code has never seen (tests/response_shapes.h;
// the 1.5x target of docs/capture.md): brackets of a real sky through each curve, with photon, read and
// 0.6 DN code noise and clipping; the merge through the recovered curve (`weighted`) is
// compared with the merge through the true curve, median and p90 relative error after one
// global scale. The full table (6 shapes x 12 bracket sets, and the held-out EMoR family) is bench/results/capture-response/capture-response.md.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <fstream>
#include <filesystem>
#include <string>
#include <vector>

#include "camera_response.h"
#include "emor_prior.h"
#include "skycal/testing/response_shapes.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/core/error.h"

namespace skycal {
namespace {

using capture::MergeBrackets;
using capture::MergeOptions;
using capture::ResponseModel;
using capture::ResponseModelName;

// The scene behind the brackets: the real sunset frame (datasets/fetch_real_skies.sh), or a
// rendered clear sky without it. The tests whose thresholds were set on the real frame skip
// without it, as real_sky_test does, rather than fail on a download.
bool RealScene() { return std::filesystem::exists(std::string(SKYCAL_SOURCE_DIR) + "/datasets/real/sunset.exr"); }
#define SKIP_WITHOUT_REAL_SCENE() \
  if (!RealScene()) GTEST_SKIP() << "datasets/real/sunset.exr absent: run datasets/fetch_real_skies.sh"

const ImageRGB& Scene() {
  static std::string source;
  static const ImageRGB scene = synthetic::LoadBracketScene(512, 256, &source);
  return scene;
}

struct Outcome {
  synthetic::ShapeMergeError known, weighted, linear;
};

Outcome MergeThrough(const synthetic::ResponseShape& shape, int n, double ev) {
  synthetic::ShapeBracketSpec spec;
  spec.brackets = n;
  spec.ev_step = ev;
  const synthetic::SyntheticBrackets s = synthetic::MakeShapeBrackets(Scene(), shape, spec);
  MergeOptions known;
  known.response_curve = s.truth_response;
  MergeOptions weighted;
  weighted.response = ResponseModel::kWeighted;
  MergeOptions linear;  // control: a wrong fixed curve
  linear.response = ResponseModel::kLinear;
  Outcome o{synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, known).radiance, s),
            synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, weighted).radiance, s),
            synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, linear).radiance, s)};
  std::printf("[measured] %-28s %d brackets %.0f EV: known %.4f/%.4f weighted %.4f/%.4f (x%.2f/x%.2f, RGB %.3f %.3f %.3f) "
              "linear %.4f/%.4f\n",
              shape.name.c_str(), n, ev, o.known.median, o.known.p90, o.weighted.median, o.weighted.p90,
              o.weighted.median / o.known.median, o.weighted.p90 / o.known.p90, o.weighted.channel[0],
              o.weighted.channel[1], o.weighted.channel[2], o.linear.median, o.linear.p90);
  return o;
}

// The target, 1.5x the known-response merge, on the shapes whose top code is a
// well-defined full scale (finite slope at white), over short and long bracket sets.
TEST(ResponseRecovery, WithinOneAndAHalfOfTheKnownResponseOnUnseenCurves) {
  SKIP_WITHOUT_REAL_SCENE();
  const auto shapes = synthetic::UnseenResponseShapes();
  const std::vector<std::tuple<int, int, double>> cases = {{0, 9, 1.0}, {1, 5, 3.0}, {1, 5, 2.0}, {2, 3, 3.0}};
  for (const auto& [shape, n, ev] : cases) {
    const Outcome o = MergeThrough(shapes[shape], n, ev);
    EXPECT_LT(o.weighted.median, 1.5 * o.known.median) << shapes[shape].name << " " << n << " brackets";
    EXPECT_LT(o.weighted.p90, 1.5 * o.known.p90) << shapes[shape].name << " " << n << " brackets";
    // Control: the check can fail; a linear curve through these shapes is far off.
    EXPECT_GT(o.linear.median, 1.5 * o.known.median) << shapes[shape].name;
  }
}

// Not yet at the target (bench/results/capture-response/capture-response.md): the logistic-in-stops curve
// with 2-3 EV spacing, and per-channel curves whose knee is nearly flat at white, where the
// channels' balance rests on extrapolating ln f over the top codes 253..255 (the gauge:
// every channel's top code is full scale). Bounds at the measured level with margin, so a
// regression shows; the numbers are printed.
TEST(ResponseRecovery, HarderCurvesStayBounded) {
  SKIP_WITHOUT_REAL_SCENE();
  const auto shapes = synthetic::UnseenResponseShapes();
  const Outcome logs = MergeThrough(shapes[0], 5, 2.0);
  EXPECT_LT(logs.weighted.median, 2.0 * logs.known.median);
  EXPECT_LT(logs.weighted.p90, 2.0 * logs.known.p90);
  const Outcome per_channel = MergeThrough(shapes[3], 5, 2.0);
  EXPECT_LT(per_channel.weighted.median, 3.5 * per_channel.known.median);
  EXPECT_LT(per_channel.weighted.p90, 3.5 * per_channel.known.p90);
  for (double c : per_channel.weighted.channel) EXPECT_NEAR(c, 1.0, 0.1);
}

// `--response auto` (the default) on curves made here, not the bench's: one shape shared by
// the channels (a logistic in stops, long 3-EV set: where `weighted` alone misses) and three
// different curves per channel. The target after one scale per channel (the balance the
// colour chart fixes): within 1.5x of the known-response merge, median and p90; auto must
// pick debevec for the first and weighted for the second (the shape difference between).
TEST(ResponseRecovery, AutoMeetsTheTargetOnSharedAndPerChannelCurves) {
  struct Case {
    synthetic::ResponseShape shape;
    int n;
    double ev;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"shared logistic", {synthetic::LogisticInStops(0.75, -1.8), synthetic::LogisticInStops(0.75, -1.8),
                            synthetic::LogisticInStops(0.75, -1.8)}},
       7, 3.0, "debevec"},
      {{"per-channel", {synthetic::GammaKnee(2.0, 1.2), synthetic::FilmToeShoulder(9.0, 2.3), synthetic::LogisticInStops(0.9, -2.5)}},
       5, 2.0, "weighted"}};
  for (const Case& k : cases) {
    synthetic::ShapeBracketSpec spec;
    spec.brackets = k.n;
    spec.ev_step = k.ev;
    spec.seed = 5;
    const synthetic::SyntheticBrackets s = synthetic::MakeShapeBrackets(Scene(), k.shape, spec);
    MergeOptions known;
    known.response_curve = s.truth_response;
    const auto truth = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, known).radiance, s);
    const capture::MergeResult au = MergeBrackets(s.brackets, MergeOptions());  // the default: auto
    const auto a = synthetic::EvaluateShapeMerge(au.radiance, s);
    MergeOptions other;
    other.response = k.expect == "debevec" ? ResponseModel::kWeighted : ResponseModel::kDebevec;
    const auto o = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, other).radiance, s);
    const auto& choice = au.report["response"]["calibration"]["auto"];
    std::printf("[measured] auto on %s (%d brackets, %.0f EV): shape difference %.4f -> %s; x%.2f / x%.2f of the known merge "
                "(median / p90, per-channel balance); %s instead x%.2f / x%.2f\n",
                k.shape.name.c_str(), k.n, k.ev, choice["channel_shape_difference"].get<double>(),
                choice["chose"].get<std::string>().c_str(), a.median_balanced / truth.median_balanced,
                a.p90_balanced / truth.p90_balanced, ResponseModelName(other.response),
                o.median_balanced / truth.median_balanced, o.p90_balanced / truth.p90_balanced);
    EXPECT_EQ(choice["chose"], k.expect) << k.shape.name;
    EXPECT_LT(a.median_balanced, 1.5 * truth.median_balanced) << k.shape.name;
    EXPECT_LT(a.p90_balanced, 1.5 * truth.p90_balanced) << k.shape.name;
  }
}

// The reported case: one S-shaped curve with a strong shoulder in the three channels (a
// logistic in stops, slope 1.2 per stop centred 3 stops under full scale: codes 200..255
// span 2 stops), 5 brackets 2 EV apart. `auto` sees one shape and recovers one curve for
// the three channels: within 1.5x of the known-response merge after one global scale
// (median and p90). Control: Debevec's solve per channel (what auto used before, and what
// `--response debevec` still does), whose channels each extrapolate their own top codes,
// misses the target by the channels' imbalance.
TEST(ResponseRecovery, SharedShoulderCurveOneCurveForTheThreeChannels) {
  const synthetic::ToneCurve shoulder = synthetic::LogisticInStops(1.2, -3.0);
  const synthetic::ResponseShape shape{"shoulder", {shoulder, shoulder, shoulder}};
  synthetic::ShapeBracketSpec spec;  // 5 brackets 2 EV apart, photon + read + DN noise, clipping
  const synthetic::SyntheticBrackets s = synthetic::MakeShapeBrackets(Scene(), shape, spec);
  MergeOptions known;
  known.response_curve = s.truth_response;
  const auto k = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, known).radiance, s);
  const capture::MergeResult au = MergeBrackets(s.brackets, MergeOptions());
  const auto a = synthetic::EvaluateShapeMerge(au.radiance, s);
  MergeOptions per_channel;
  per_channel.response = ResponseModel::kDebevec;
  const auto d = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, per_channel).radiance, s);
  std::printf("[measured] shoulder, 5 brackets 2 EV: known %.4f / %.4f; auto (one curve) x%.2f / x%.2f; debevec per channel "
              "x%.2f / x%.2f (median / p90, one global scale)\n",
              k.median, k.p90, a.median / k.median, a.p90 / k.p90, d.median / k.median, d.p90 / k.p90);
  const auto& cal = au.report["response"]["calibration"];
  EXPECT_EQ(cal["auto"]["chose"], "debevec");
  EXPECT_EQ(cal["channels"], "one curve for the three channels");
  EXPECT_LT(a.median, 1.5 * k.median);
  EXPECT_LT(a.p90, 1.5 * k.p90);
  EXPECT_GT(std::max(d.median / k.median, d.p90 / k.p90), 1.5);  // control: the old choice misses
  EXPECT_TRUE(au.report["warnings"].empty()) << au.report["warnings"].dump();
}

// Brackets that cannot determine the curve say so. A steep logistic (2.5 per stop: ~160 codes
// per stop in the mid-tones) 2 EV apart: no pixel is well exposed in the mid-tones and in a
// neighbouring bracket, so those codes are tied to nothing and the curve there is the
// smoothness prior's guess: the merge report carries a warning naming the codes. Two
// brackets 8 EV apart: hardly any pixel is well exposed in both. Controls: the same curve
// 1 EV apart, and a gamma 2.2 curve 2 EV apart, are determined (no warning).
TEST(ResponseRecovery, BracketsThatCannotDetermineTheCurveSaySo) {
  SKIP_WITHOUT_REAL_SCENE();
  const synthetic::ToneCurve steep = synthetic::LogisticInStops(2.5, -2.0);
  const synthetic::ToneCurve gamma = [](double x) { return std::pow(x, 1.0 / 2.2); };
  struct Case {
    synthetic::ToneCurve curve;
    int n;
    double ev;
    const char* expect;  // a phrase of the warning, or nullptr: none
  };
  const std::vector<Case> cases = {{steep, 5, 2.0, "interpolated, not measured"},
                                   {gamma, 2, 8.0, "too few brackets, or too far apart"},
                                   {steep, 9, 1.0, nullptr},
                                   {gamma, 5, 2.0, nullptr}};
  for (const Case& k : cases) {
    synthetic::ShapeBracketSpec spec;
    spec.brackets = k.n;
    spec.ev_step = k.ev;
    const synthetic::SyntheticBrackets s = synthetic::MakeShapeBrackets(Scene(), {"case", {k.curve, k.curve, k.curve}}, spec);
    const capture::MergeResult r = MergeBrackets(s.brackets, MergeOptions());
    const nlohmann::json& w = r.report["warnings"];
    const nlohmann::json& det = r.report["response"]["determinacy"]["channels"][1];
    std::printf("[measured] %d brackets %.0f EV: %zu warnings; G: %.3f of the pixels linked, %d codes unlinked\n", k.n, k.ev,
                w.size(), det["linked_pixel_fraction"].get<double>(), det["unlinked_codes"].get<int>());
    if (k.expect == nullptr) {
      EXPECT_TRUE(w.empty()) << k.n << " brackets " << k.ev << " EV: " << w.dump();
      continue;
    }
    ASSERT_EQ(w.size(), 3u) << w.dump();  // one per channel: the curve is the same in each
    EXPECT_NE(w[0].get<std::string>().find(k.expect), std::string::npos) << w[0];
  }
}

// The EMoR curve with coefficients c (datasets/response/emor_basis.csv), as a tone curve.
synthetic::ToneCurve EmorCurve(const std::array<double, 6>& c) {
  const synthetic::EmorBasis basis = capture::ReadEmorBasis(std::string(SKYCAL_SOURCE_DIR) + "/datasets/response/emor_basis.csv");
  return synthetic::SampledCurve(capture::EmorCurve(basis, c));
}

// The cause of the held-out family's misses (docs/capture.md): brackets a constant 2 EV apart
// cannot see a part of the curve periodic in 2 stops, and Debevec's smoothness alone picks
// the wrong one for a camera curve that bends within one step. A curve of the EMoR space made
// here (not one of the bench's draws), with such a bend (its local slope in log-log falls from
// ~1 at white to ~0.35 two stops down and rises again), 5 brackets 2 EV apart: with the EMoR
// prior (the default) within 1.5x of the known-response merge; control: the prior off misses
// by 2x or more; the same with the exposure times a camera writes (1/15 s for 1/16: the steps
// look 1.9 to 2.1 EV). Brackets at unequal steps (1.7, 1.8, 2.1, 2.4 EV) leave no exactly
// periodic part: the prior is not used and the report says why (their error is printed: a
// nearly periodic part stays weakly determined, docs/capture.md).
TEST(ResponseRecovery, ConstantStepsLeaveAPeriodicPartTheEmorPriorPicks) {
  const synthetic::ToneCurve t = EmorCurve({1.5, -2.0, -0.3, 0.1, 0.0, 0.0});
  for (int i = 1; i <= 1000; ++i) ASSERT_GT(t(i / 1000.0), t((i - 1) / 1000.0)) << "the test's curve must increase";
  const synthetic::ResponseShape shape{"EMoR (1.5, -2.0, -0.3, 0.1)", {t, t, t}};
  for (const std::string steps : {"2 EV", "2 EV, nominal times", "unequal"}) {
    const bool constant = steps != "unequal";
    synthetic::ShapeBracketSpec spec;  // 5 brackets 2 EV apart
    spec.seed = 3;
    if (!constant) spec.stops = {-4.0, -2.3, -0.5, 1.6, 4.0};
    synthetic::SyntheticBrackets s = synthetic::MakeShapeBrackets(Scene(), shape, spec);
    if (steps == "2 EV, nominal times") {  // 1/960 .. 4/15 s as a camera labels them (EXIF)
      const double nominal[5] = {1.0 / 1000, 1.0 / 250, 1.0 / 60, 1.0 / 15, 1.0 / 4};
      for (int i = 0; i < 5; ++i) s.brackets[i].exposure_time_s = nominal[i];
    }
    MergeOptions known;
    known.response_curve = s.truth_response;
    const auto k = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, known).radiance, s);
    const capture::MergeResult with = MergeBrackets(s.brackets, MergeOptions());
    MergeOptions off;
    off.emor_prior = false;
    const auto a = synthetic::EvaluateShapeMerge(with.radiance, s);
    const auto b = synthetic::EvaluateShapeMerge(MergeBrackets(s.brackets, off).radiance, s);
    const nlohmann::json& prior = with.report["response"]["calibration"]["emor_prior"];
    std::printf("[measured] %s steps: known %.4f / %.4f; auto x%.2f / x%.2f (prior %s); without the prior x%.2f / x%.2f\n",
                steps.c_str(), k.median, k.p90, a.median / k.median, a.p90 / k.p90, prior.dump().c_str(),
                b.median / k.median, b.p90 / k.p90);
    ASSERT_EQ(with.report["response"]["calibration"]["auto"]["chose"], "debevec");
    if (constant) {
      EXPECT_TRUE(prior["used"].get<bool>());
      EXPECT_NEAR(prior["undetermined_period_stops"].get<double>(), 2.0, 0.02);
      EXPECT_LT(a.median, 1.5 * k.median);
      EXPECT_LT(a.p90, 1.5 * k.p90);
      EXPECT_GT(std::max(b.median / k.median, b.p90 / k.p90), 2.0);  // control: the smoothness alone
    } else {
      EXPECT_FALSE(prior["used"].get<bool>());
      EXPECT_NE(prior["why"].get<std::string>().find("not multiples of one step"), std::string::npos) << prior;
      EXPECT_EQ(a.median, b.median);  // the prior off and unused: the same merge
    }
  }
}

// The period the brackets leave undetermined: the largest step every step is a whole
// multiple of (>= a quarter stop), 0 when none.
TEST(ResponseRecovery, UndeterminedPeriodOfBracketSteps) {
  const double ln2 = std::log(2.0);
  auto period = [&](std::vector<double> stops) {
    for (double& v : stops) v *= ln2;
    return capture::detail::UndeterminedPeriod(stops) / ln2;
  };
  EXPECT_NEAR(period({-4, -2, 0, 2, 4}), 2.0, 1e-12);
  EXPECT_NEAR(period({4, 0, -2, 2}), 2.0, 1e-12);    // order does not matter
  EXPECT_NEAR(period({0, 1, 3, 4}), 1.0, 1e-12);     // steps 1, 2, 1
  EXPECT_NEAR(period({0, 2, 3.5}), 0.5, 1e-12);      // steps 2 and 1.5: both multiples of 0.5
  EXPECT_NEAR(period({0, 2.02, 4}), 2.0, 0.03);      // metadata rounding within 5% of a step
  // Nominal shutter speeds of a 2 EV series: 1/4000 1/1000 1/250 1/60 1/15 1/4 1 s
  // (steps 2, 2, 2.06, 2, 1.91, 2 stops): one step of 2.
  std::vector<double> nominal;
  for (double t : {1.0 / 4000, 1.0 / 1000, 1.0 / 250, 1.0 / 60, 1.0 / 15, 1.0 / 4, 1.0}) nominal.push_back(std::log2(t));
  EXPECT_NEAR(period(nominal), 2.0, 0.01);
  EXPECT_NEAR(period({0, 2, 3.3}), 0.66, 0.01);      // 2 and 1.3: both near multiples of 0.66
  EXPECT_EQ(period({0, 1.7, 3.5, 5.6, 8.0}), 0.0);   // steps 1.7, 1.8, 2.1, 2.4: none >= 0.25
  EXPECT_EQ(period({0}), 0.0);
}

// AdoptPeriodicPart changes only what the brackets cannot see. A prior that differs from the
// free curve by a wiggle periodic in the step (plus a constant) is taken whole. One that
// differs by a bump one stop wide is visible to the brackets: taken whole it would spread a
// pixel's brackets apart (control), while the adopted curve explains noise-free codes of a
// gamma-2.2 camera 2 EV apart as well as the free (true) curve does.
TEST(ResponseRecovery, AdoptPeriodicPartChangesOnlyTheUndeterminedPart) {
  const double L = 2.0 * std::log(2.0), pi = 3.14159265358979;
  std::vector<double> g(256), wiggled(256), bumped(256);
  std::vector<float> w(256);
  for (int z = 0; z < 256; ++z) {
    g[z] = 2.2 * std::log((z + 0.5) / 255.5);
    wiggled[z] = g[z] + 0.3 + 0.04 * std::sin(2.0 * pi * g[z] / L);
    bumped[z] = g[z] + 0.3 * std::exp(-std::pow((g[z] + 3.0) / 0.7, 2.0));
    w[z] = 1.0f - std::fabs(2.0f * z / 255.0f - 1.0f);
  }
  const std::vector<double> a = capture::detail::AdoptPeriodicPart(g, wiggled, L, 5, 250, w);
  for (int z = 10; z < 246; ++z) EXPECT_NEAR(a[z], wiggled[z], 2e-3) << z;
  const std::vector<double> b = capture::detail::AdoptPeriodicPart(g, bumped, L, 5, 250, w);
  // RMS spread of gg(z_j) - ln k_j over each pixel's codes 40..249 (above 40 the 8-bit
  // rounding costs < 0.03 in ln), pixels of random radiance, brackets 2 EV apart.
  auto spread = [&](const std::vector<double>& gg) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-10.0, 0.0);
    double ss = 0.0;
    int count = 0;
    for (int p = 0; p < 2000; ++p) {
      const double ln_e = u(rng) * std::log(2.0);
      std::vector<double> v;
      for (int j = 0; j < 5; ++j) {
        const double ln_k = -2.0 * j * std::log(2.0);
        const long z = std::lround(255.5 * std::exp((ln_e + ln_k) / 2.2) - 0.5);
        if (z >= 40 && z < 250) v.push_back(gg[z] - ln_k);
      }
      if (v.size() < 2) continue;
      double mean = 0.0;
      for (double x : v) mean += x / v.size();
      for (double x : v) ss += (x - mean) * (x - mean), ++count;
    }
    return std::sqrt(ss / count);
  };
  const double free = spread(g), adopted = spread(b), whole = spread(bumped);
  double moved = 0.0;
  for (int z = 6; z < 250; ++z) moved = std::max(moved, std::fabs(b[z] - g[z] - (b[128] - g[128])));
  std::printf("[measured] spread of a pixel's brackets (ln): free %.4f, adopted %.4f, the bumped prior whole %.4f; moved %.3f\n",
              free, adopted, whole, moved);
  EXPECT_LT(adopted, free + 0.003);
  EXPECT_GT(whole, 3.0 * adopted);  // control
  EXPECT_GT(moved, 0.02);           // it did move (by the bump's periodic part)
}

// The EMoR fit recovers a curve of the space from quantised codes: brackets 2 EV apart of
// random radiances through a known EMoR curve, codes rounded to 8 bits. Its inverse within
// 0.01 in ln over the well-exposed codes; control: one coefficient cannot draw it.
TEST(ResponseRecovery, EmorFitRecoversACurveOfTheSpace) {
  std::string why;
  const capture::EmorBasis* basis = capture::detail::BundledEmorBasis(&why);
  ASSERT_NE(basis, nullptr) << why;
  const std::array<double, 6> c = {0.8, -1.2, 0.3, -0.1, 0.05, 0.0};
  const synthetic::ToneCurve t = synthetic::SampledCurve(capture::EmorCurve(*basis, c));
  const std::vector<double> ln_k = {-8 * std::log(2.0), -6 * std::log(2.0), -4 * std::log(2.0), -2 * std::log(2.0), 0.0};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-9.0, 0.0);
  std::vector<uint8_t> codes;
  for (int p = 0; p < 400; ++p) {
    const double ln_e = u(rng) * std::log(2.0);
    for (double lk : ln_k) codes.push_back(static_cast<uint8_t>(std::lround(255.0 * t(std::min(1.0, std::exp(ln_e + lk))))));
  }
  std::vector<double> start(256);
  for (int z = 0; z < 256; ++z) start[z] = std::log((z + 0.5) / 255.5);  // a linear camera's
  auto worst = [&](int coefficients) {
    const capture::detail::EmorFit fit = capture::detail::FitEmorToSamples(*basis, codes, 5, ln_k, 5, 250, start, coefficients);
    EXPECT_TRUE(fit.usable) << fit.why;
    double e = 0.0;
    for (int z = 10; z < 246; ++z) e = std::max(e, std::fabs(fit.g[z] - std::log(synthetic::InvertCurve(t, z / 255.0))));
    std::printf("[measured] EMoR fit, %d coefficients: rms %.3f codes, worst |ln f^-1 error| %.4f over codes 10..245\n",
                coefficients, fit.rms_dn, e);
    return e;
  };
  EXPECT_LT(worst(6), 0.01);
  EXPECT_GT(worst(1), 0.03);  // control
}

// A basis file that is not the EMoR table is refused naming the file and the row.
TEST(ResponseRecovery, AMalformedEmorBasisNamesFileAndRow) {
  const std::string path = (std::filesystem::temp_directory_path() / ("emor_bad_" + std::to_string(::getpid()) + ".csv")).string();
  std::ofstream(path) << "E,f0,h1,h2,h3,h4,h5,h6\n0,0,0,0,0,0,0,0\n0.001,0.008,0.1\n";
  try {
    capture::ReadEmorBasis(path);
    ADD_FAILURE() << "accepted a malformed basis";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": row 3: need 8 columns"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(capture::ReadEmorBasis(path), Error);  // missing
  EXPECT_EQ(capture::ReadEmorBasis(std::string(SKYCAL_SOURCE_DIR) + "/datasets/response/emor_basis.csv").f0.size(),
            static_cast<size_t>(capture::kEmorSamples));
}

// auto's shape test: a channel's scale (a constant in ln f) does not count; a wiggle does,
// by its RMS over the codes compared (a sine of amplitude a over whole periods: a / sqrt 2).
TEST(ResponseRecovery, ChannelShapeDifferenceIgnoresScaleAndMeasuresShape) {
  std::array<std::vector<double>, 3> g;
  for (auto& c : g) c.resize(256);
  for (int z = 0; z < 256; ++z) {
    g[0][z] = 2.2 * std::log((z + 1) / 256.0);
    g[1][z] = g[0][z] - 0.7;  // another scale
    g[2][z] = g[0][z] + 0.3;
  }
  EXPECT_NEAR(capture::detail::ChannelShapeDifference(g, 3, 252), 0.0, 1e-12);
  const double a = 0.2;
  for (int z = 0; z < 256; ++z) g[2][z] = g[0][z] + 0.3 + a * std::sin(2.0 * 3.14159265358979 * 5.0 * (z - 3) / 250.0);
  // Codes 3..252: 250 codes, five whole periods.
  EXPECT_NEAR(capture::detail::ChannelShapeDifference(g, 3, 252), a / std::sqrt(2.0), 2e-3);
}

TEST(ResponseRecovery, BadOptionsAreRefused) {
  MergeOptions o;
  o.response = ResponseModel::kWeighted;
  std::string why;
  o.weighted_high_code = 255;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("weighted_high_code"), std::string::npos) << why;
  o = MergeOptions();
  o.weighted_lambda = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("weighted_lambda"), std::string::npos) << why;
  EXPECT_EQ(capture::ParseResponseModel("weighted", "--response"), ResponseModel::kWeighted);
  EXPECT_EQ(capture::ParseResponseModel("auto", "--response"), ResponseModel::kAuto);
  o = MergeOptions();
  o.emor_coefficients = 7;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("emor_coefficients"), std::string::npos) << why;
  o = MergeOptions();
  o.auto_shape_tolerance = -0.1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("auto_shape_tolerance"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal
