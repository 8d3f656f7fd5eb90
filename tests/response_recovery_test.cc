// Camera-response recovery on tone curves the code has never seen (tests/response_shapes.h;
// the 1.5x target of docs/capture.md): brackets of a real sky through each curve, with photon, read and
// 0.6 DN code noise and clipping; the merge through the recovered curve (`weighted`) is
// compared with the merge through the true curve, median and p90 relative error after one
// global scale. The full table (5 shapes x 12 bracket sets) is bench/results/capture-response/capture-response.md.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

#include "camera_response.h"
#include "skycal/testing/response_shapes.h"
#include "skycal/capture/hdr_merge.h"

namespace skycal {
namespace {

using capture::MergeBrackets;
using capture::MergeOptions;
using capture::ResponseModel;
using capture::ResponseModelName;

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
  o.auto_shape_tolerance = -0.1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("auto_shape_tolerance"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal
