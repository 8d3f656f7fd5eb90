// HDR merge of exposure brackets (capture/hdr_merge.h): round trips through synthetic
// brackets of a real sky with known camera curve, exposures and noise (synthetic_brackets.h),
// the exposure scale, the loader (PNG, JPEG + EXIF through exiv2) and the bad inputs.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "skycal/capture/exif_exposure.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/core/error.h"
#include "skycal/testing/synthetic_brackets.h"
#include "test_util.h"

namespace skycal {
namespace {

using capture::Bracket;
using capture::MergeBrackets;
using capture::MergeOptions;
using capture::MergeResult;
using capture::ResponseModel;
using synthetic::BracketSpec;
using synthetic::CameraCurve;
using synthetic::MergeErrors;
using synthetic::SyntheticBrackets;

constexpr int kWidth = 1024, kHeight = 512;

const ImageRGB& Scene() {
  static std::string source;
  static const ImageRGB scene = synthetic::LoadBracketScene(kWidth, kHeight, &source);
  static bool printed = false;
  if (!printed) std::printf("[scene] %s, %dx%d\n", source.c_str(), scene.width, scene.height), printed = true;
  return scene;
}

SyntheticBrackets Make(CameraCurve curve, int bits = 8, unsigned seed = 1) {
  BracketSpec spec;
  spec.curve = curve;
  spec.bits = bits;
  spec.seed = seed;
  return synthetic::MakeSyntheticBrackets(Scene(), spec);
}

MergeErrors Report(const char* name, const MergeResult& r, const SyntheticBrackets& s, bool gauge) {
  const MergeErrors e = synthetic::EvaluateMerge(r, s, gauge);
  std::printf(
      "[measured] %-10s rel. error median %.4f p95 %.4f over %lld pixels well measured by >= 1 exposure (gauge %.4f %.4f "
      "%.4f%s); response rel. error median %.4f p95 %.4f max %.4f; well/over/under/gap %lld/%lld/%lld/%lld, mask "
      "mismatch %lld; timings %s\n",
      name, e.median_rel, e.p95_rel, e.pixels, e.gauge[0], e.gauge[1], e.gauge[2], gauge ? ", divided out" : "",
      e.curve_median_rel, e.curve_p95_rel, e.curve_max_rel, r.well_measured_pixels, r.over_exposed, r.under_exposed, r.gap,
      e.mask_mismatch, r.report["timings_ms"].dump().c_str());
  return e;
}

// Shared checks of a merge of the sunset brackets.
void CheckCommon(const MergeResult& r, const SyntheticBrackets& s, const MergeErrors& e) {
  const long long total = static_cast<long long>(kWidth) * kHeight;
  EXPECT_EQ(r.radiance.width, kWidth);
  EXPECT_EQ(r.well_measured_pixels + r.not_well_measured, total);
  EXPECT_GT(e.pixels, total / 2);  // most of the sky is measurable
  // The sun is clipped even at 1/4000 s: flagged, with the shortest exposure's value, a
  // lower bound of the truth.
  EXPECT_GT(r.over_exposed, 0);
  long long over_above_truth = 0;
  for (size_t p = 0; p < r.flags.size(); ++p) {
    if (!(r.flags[p] & capture::kPixelOverExposed)) continue;
    double merged = 0.0, truth = 0.0;
    for (int c = 0; c < 3; ++c) merged += r.radiance.pixels[3 * p + c] / e.gauge[c], truth += s.truth.pixels[3 * p + c];
    over_above_truth += merged > 1.1 * truth;
  }
  EXPECT_LE(over_above_truth, r.over_exposed / 100 + 1);
  // The mask agrees with the noise-free truth except where noise crosses a threshold.
  EXPECT_LT(e.mask_mismatch, total / 100);
  for (float v : r.radiance.pixels) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
}

// --- round trips ----------------------------------------------------------------------------
// Tolerances: the simulated camera's photon + read noise and 8-bit quantisation alone give
// about 0.9% median / 2.9% p95 relative error with the true curve (linear, sRGB); a
// recovered curve adds its own error (measured 1.1% / 3.2% for Debevec). Bounds leave ~1.5x
// headroom for other seeds and scenes (the rendered fallback when sunset.exr is absent).

TEST(HdrMerge, LinearRoundTrip) {
  const SyntheticBrackets s = Make(CameraCurve::kLinear);
  MergeOptions o;
  o.response = ResponseModel::kLinear;
  const MergeResult r = MergeBrackets(s.brackets, o);
  const MergeErrors e = Report("linear", r, s, false);
  CheckCommon(r, s, e);
  EXPECT_LT(e.median_rel, 0.015);
  EXPECT_LT(e.p95_rel, 0.045);
  for (double g : e.gauge) EXPECT_NEAR(g, 1.0, 0.005);  // the scale is known: no gauge
}

TEST(HdrMerge, SrgbRoundTrip) {
  const SyntheticBrackets s = Make(CameraCurve::kSrgb);
  MergeOptions o;
  o.response = ResponseModel::kSrgb;
  const MergeResult r = MergeBrackets(s.brackets, o);
  const MergeErrors e = Report("srgb", r, s, false);
  CheckCommon(r, s, e);
  EXPECT_LT(e.median_rel, 0.015);
  EXPECT_LT(e.p95_rel, 0.045);
  for (double g : e.gauge) EXPECT_NEAR(g, 1.0, 0.005);
}

TEST(HdrMerge, DebevecRoundTrip) {
  const SyntheticBrackets s = Make(CameraCurve::kFilmic);
  MergeOptions o;
  o.response = ResponseModel::kDebevec;
  const MergeResult r = MergeBrackets(s.brackets, o);
  const MergeErrors e = Report("debevec", r, s, true);
  const MergeErrors raw = Report("debevec (scale not divided out)", r, s, false);
  CheckCommon(r, s, e);
  EXPECT_LT(e.median_rel, 0.02);
  EXPECT_LT(e.p95_rel, 0.05);
  // The curve's scale (top code = 1, extrapolated past the last well-exposed code) and
  // white balance (scale per channel): measured 1.06-1.09, spread 2.5% (rendered sky: 4.2%).
  for (double g : e.gauge) EXPECT_NEAR(g, 1.0, 0.15);
  EXPECT_LT(std::max({e.gauge[0], e.gauge[1], e.gauge[2]}) / std::min({e.gauge[0], e.gauge[1], e.gauge[2]}), 1.06);
  EXPECT_LT(raw.curve_median_rel, 0.12);
  EXPECT_EQ(r.response_levels, 256);
  EXPECT_EQ(r.report["response"]["calibration"]["decreasing_steps"], 0);

  // Baseline: OpenCV's CalibrateDebevec at its default lambda, which also fits clipped and
  // black samples: the top code lands ~4x too high, so the scale is off by that much.
  MergeOptions cv = o;
  cv.opencv_calibration = true;
  cv.lambda = 10.0;
  const MergeResult base = MergeBrackets(s.brackets, cv);
  const MergeErrors be = Report("debevec, OpenCV baseline", base, s, true);
  EXPECT_LT(e.p95_rel, be.p95_rel);
  EXPECT_LT(std::fabs(std::log(e.gauge[1])), std::fabs(std::log(be.gauge[1])));
}

TEST(HdrMerge, RobertsonRoundTrip) {
  const SyntheticBrackets s = Make(CameraCurve::kFilmic);
  MergeOptions o;
  o.response = ResponseModel::kRobertson;
  const MergeResult r = MergeBrackets(s.brackets, o);
  const MergeErrors e = Report("robertson", r, s, true);
  CheckCommon(r, s, e);
  EXPECT_LT(e.median_rel, 0.025);
  EXPECT_LT(e.p95_rel, 0.06);
  for (double g : e.gauge) EXPECT_NEAR(g, 1.0, 0.15);
  MergeOptions cv = o;
  cv.opencv_calibration = true;
  cv.robertson_threshold = 0.01;  // OpenCV's default and meaning
  Report("robertson, OpenCV baseline", MergeBrackets(s.brackets, cv), s, true);
}

TEST(HdrMerge, SixteenBitBrackets) {
  const SyntheticBrackets s = Make(CameraCurve::kLinear, 16);
  MergeOptions o;
  o.response = ResponseModel::kLinear;
  const MergeResult r = MergeBrackets(s.brackets, o);
  const MergeErrors e = Report("linear16", r, s, false);
  EXPECT_EQ(r.response_levels, 65536);
  EXPECT_LT(e.median_rel, 0.015);
  EXPECT_LT(e.p95_rel, 0.045);
  // Debevec calibrates on codes rounded to 8 bits and interpolates the curve for 16 bits.
  o.response = ResponseModel::kDebevec;
  const MergeResult d = MergeBrackets(s.brackets, o);
  const MergeErrors de = Report("debevec16", d, s, true);
  EXPECT_EQ(d.response_levels, 256);
  EXPECT_LT(de.median_rel, 0.03);
  EXPECT_LT(de.p95_rel, 0.08);
}

// A recovered curve reused for another frame (a time-lapse) skips calibration and gives the
// same numbers as the merge that recovered it.
TEST(HdrMerge, FixedCurveReuse) {
  const SyntheticBrackets s = Make(CameraCurve::kFilmic);
  MergeOptions o;
  const MergeResult first = MergeBrackets(s.brackets, o);
  MergeOptions fixed;
  fixed.response_curve = first.response_curve;
  const MergeResult again = MergeBrackets(s.brackets, fixed);
  EXPECT_EQ(again.report["response"]["source"], "fixed_curve");
  EXPECT_FALSE(again.report["response"].contains("calibration"));
  EXPECT_EQ(again.radiance.pixels, first.radiance.pixels);
}

// --- exposure scale ----------------------------------------------------------------------------

// Radiance is value / (t * ISO/100 / N^2): the same sky shot at f/5.6, ISO 200 (brackets
// 2.04 stops brighter) merges to the same numbers within noise.
TEST(HdrMerge, ExposureScaleAcrossSettings) {
  const SyntheticBrackets a = Make(CameraCurve::kLinear);
  BracketSpec spec;
  spec.curve = CameraCurve::kLinear;
  spec.f_number = 5.6;
  spec.iso = 200;
  spec.gain = a.gain;  // same camera, same scene
  spec.seed = 2;
  const SyntheticBrackets b = synthetic::MakeSyntheticBrackets(Scene(), spec);
  MergeOptions o;
  o.response = ResponseModel::kLinear;
  const MergeResult ra = MergeBrackets(a.brackets, o), rb = MergeBrackets(b.brackets, o);
  std::vector<double> ratio;
  for (size_t p = 0; p < a.truth_well.size(); ++p)
    if (a.truth_well[p] && b.truth_well[p]) ratio.push_back(rb.radiance.pixels[3 * p + 1] / ra.radiance.pixels[3 * p + 1]);
  const double median = synthetic::Quantile(ratio, 0.5);
  std::printf("[measured] f/8 ISO 100 vs f/5.6 ISO 200: median ratio %.5f over %zu pixels; exposure_scale %.6g vs %.6g\n",
              median, ratio.size(), ra.exposure_scale, rb.exposure_scale);
  EXPECT_NEAR(median, 1.0, 0.003);
  EXPECT_TRUE(ra.exposure_uses_aperture_iso);
  EXPECT_NEAR(ra.exposure_scale, 64.0 / (1.0 / 60), 1e-6 * 64 * 60);  // middle bracket 1/60 s, f/8, ISO 100
  EXPECT_NEAR(ra.exposure_factors[0], (1.0 / 4000) / 64.0, 1e-15);
}

// Brackets on disk: PNG codes come back in RGB order, explicit times; without EXIF there is
// no f-number / ISO, so k = t and the radiance is the in-memory one (f/8, ISO 100) / 64.
TEST(HdrMerge, PngFilesWithExplicitTimes) {
  const SyntheticBrackets s = Make(CameraCurve::kSrgb);
  testing::ScratchDir dir("hdr_png");
  const std::vector<std::string> paths = synthetic::WriteBracketsPng(s, dir.path().string());
  nlohmann::json load_report;
  const std::vector<Bracket> loaded = capture::LoadBrackets(paths, BracketSpec().exposure_times_s, 0, &load_report);
  ASSERT_EQ(loaded.size(), s.brackets.size());
  for (size_t i = 0; i < loaded.size(); ++i) {
    EXPECT_EQ(loaded[i].image.rgb, s.brackets[i].image.rgb) << paths[i];
    EXPECT_TRUE(std::isnan(loaded[i].f_number));
    EXPECT_EQ(load_report["files"][i]["exposure_time_source"], "explicit");
  }
  MergeOptions o;
  o.response = ResponseModel::kSrgb;
  const MergeResult from_files = MergeBrackets(loaded, o), in_memory = MergeBrackets(s.brackets, o);
  EXPECT_FALSE(from_files.exposure_uses_aperture_iso);
  for (size_t i = 0; i < in_memory.radiance.pixels.size(); i += 997)
    EXPECT_NEAR(64.0f * from_files.radiance.pixels[i], in_memory.radiance.pixels[i], 1e-5f * in_memory.radiance.pixels[i]);
}

// --- flags on hand-made pixels -------------------------------------------------------------------

TEST(HdrMerge, ClippedBlackAndGapPixels) {
  // 4 pixels x 2 brackets (t = 1/100 s, 1/25 s), linear 8-bit codes, grey:
  //   0: 255 / 255 clipped in both -> over, shortest's value 1 / 0.01 = 100
  //   1:   2 /   3 black in both   -> under, longest's value (3/255) / 0.04
  //   2:   2 / 255 black then clipped -> gap, midway between the two bounds
  //   3:  51 / 204 well exposed in both
  auto make = [](double t, std::vector<uint16_t> codes) {
    Bracket b;
    b.path = "t=" + std::to_string(t);
    b.exposure_time_s = t;
    b.image.width = 4;
    b.image.height = 1;
    for (uint16_t c : codes) b.image.rgb.insert(b.image.rgb.end(), {c, c, c});
    return b;
  };
  const std::vector<Bracket> br = {make(0.04, {255, 3, 255, 204}), make(0.01, {255, 2, 2, 51})};  // any order
  MergeOptions o;
  o.response = ResponseModel::kLinear;
  const MergeResult r = MergeBrackets(br, o);
  EXPECT_EQ(r.flags[0], capture::kPixelOverExposed);
  EXPECT_EQ(r.flags[1], capture::kPixelUnderExposed);
  EXPECT_EQ(r.flags[2], capture::kPixelGap);
  EXPECT_EQ(r.flags[3], 0);
  EXPECT_EQ(r.well_measured, (std::vector<float>{0, 0, 0, 1}));
  EXPECT_EQ(r.over_exposed, 1);
  EXPECT_EQ(r.under_exposed, 1);
  EXPECT_EQ(r.gap, 1);
  EXPECT_EQ(r.not_well_measured, 3);
  EXPECT_FLOAT_EQ(r.radiance.at(0, 0, 0), 100.0f);
  EXPECT_FLOAT_EQ(r.radiance.at(1, 0, 0), 3.0f / 255 / 0.04f);
  EXPECT_FLOAT_EQ(r.radiance.at(2, 0, 0), 0.5f * (2.0f / 255 / 0.01f + 1.0f / 0.04f));
  EXPECT_NEAR(r.radiance.at(3, 0, 0), 20.0f, 1e-4f);  // 51/255/0.01 = 204/255/0.04 = 20
  EXPECT_EQ(r.report["pixels"]["not_well_measured"], 3);
}

TEST(HdrMerge, ThreadsGiveIdenticalResults) {
  const SyntheticBrackets s = Make(CameraCurve::kFilmic);
  MergeOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const MergeResult a = MergeBrackets(s.brackets, one), b = MergeBrackets(s.brackets, two);
  EXPECT_EQ(a.radiance.pixels, b.radiance.pixels);
  EXPECT_EQ(a.response_curve, b.response_curve);
}

// --- bad input -------------------------------------------------------------------------------------

template <class F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no skycal::Error thrown)";
}

std::vector<Bracket> SmallBrackets() {
  std::vector<Bracket> out;
  for (int i = 0; i < 3; ++i) {
    Bracket b;
    b.path = "small_" + std::to_string(i) + ".png";
    b.exposure_time_s = 0.01 * (1 << (2 * i));
    b.image.width = 8;
    b.image.height = 4;
    b.image.rgb.assign(8 * 4 * 3, static_cast<uint16_t>(40 + 60 * i));
    out.push_back(b);
  }
  return out;
}

TEST(HdrMergeErrors, DifferentSizes) {
  auto br = SmallBrackets();
  br[1].image.width = 7;
  br[1].image.rgb.resize(7 * 4 * 3);
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("small_1.png"), std::string::npos) << m;
  EXPECT_NE(m.find("7x4"), std::string::npos) << m;
  EXPECT_NE(m.find("small_0.png"), std::string::npos) << m;
}

TEST(HdrMergeErrors, FailedResponseRecoveryNamesEachFileAndTheField) {
  // Every bracket black but the longest (code 100 everywhere): no pixel has two codes in the
  // recovery's range, and the message names the options field, each file shortest first
  // with its time and its share of usable samples (0% black, 100% for the longest).
  auto br = SmallBrackets();
  br[0].image.rgb.assign(br[0].image.rgb.size(), 0);
  br[1].image.rgb.assign(br[1].image.rgb.size(), 0);
  br[2].image.rgb.assign(br[2].image.rgb.size(), 100);
  for (ResponseModel model : {ResponseModel::kWeighted, ResponseModel::kRobertson}) {
    MergeOptions o;
    o.response = model;
    const std::string m = ErrorOf([&] { MergeBrackets(br, o); });
    EXPECT_NE(m.find("merge options field 'response' = " + std::string(ResponseModelName(model))), std::string::npos)
        << m;
    const size_t a = m.find("'small_0.png' (t = 0.01 s, 0%)"), b = m.find("'small_1.png' (t = 0.04 s, 0%)"),
                 c = m.find("'small_2.png' (t = 0.16 s, 100%)");
    EXPECT_NE(a, std::string::npos) << m;
    EXPECT_NE(b, std::string::npos) << m;
    EXPECT_NE(c, std::string::npos) << m;
    EXPECT_LT(a, b) << m;
    EXPECT_LT(b, c) << m;
  }
}

TEST(HdrMergeErrors, DifferentBitDepths) {
  auto br = SmallBrackets();
  br[2].image.bits = 16;
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("small_2.png: 16-bit"), std::string::npos) << m;
}

TEST(HdrMergeErrors, OnlyOneExposure) {
  auto br = SmallBrackets();
  br.resize(1);
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("at least two exposures"), std::string::npos) << m;
  EXPECT_NE(m.find("small_0.png"), std::string::npos) << m;
  EXPECT_NE(ErrorOf([&] { MergeBrackets({}, MergeOptions()); }).find("got 0"), std::string::npos);
}

TEST(HdrMergeErrors, NonPositiveOrMissingTime) {
  for (double t : {0.0, -0.01, double(INFINITY)}) {
    auto br = SmallBrackets();
    br[1].exposure_time_s = t;
    const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
    EXPECT_NE(m.find("small_1.png: exposure time must be finite and > 0"), std::string::npos) << m;
  }
  auto br = SmallBrackets();
  br[2].exposure_time_s = NAN;
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("small_2.png: exposure time missing"), std::string::npos) << m;
}

TEST(HdrMergeErrors, DuplicateTimes) {
  auto br = SmallBrackets();
  br[2].exposure_time_s = br[0].exposure_time_s;
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("same exposure"), std::string::npos) << m;
  EXPECT_NE(m.find("small_0.png"), std::string::npos) << m;
  EXPECT_NE(m.find("small_2.png"), std::string::npos) << m;
}

TEST(HdrMergeErrors, FNumberForSomeBracketsOnly) {
  auto br = SmallBrackets();
  br[0].f_number = br[2].f_number = 8.0;
  const std::string m = ErrorOf([&] { MergeBrackets(br, MergeOptions()); });
  EXPECT_NE(m.find("small_1.png: f-number unknown"), std::string::npos) << m;
}

TEST(HdrMergeErrors, InvalidOptions) {
  std::string why;
  MergeOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.lambda = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("lambda"), std::string::npos);
  o = MergeOptions();
  o.low_threshold = 0.9;
  o.high_threshold = 0.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("low_threshold"), std::string::npos);
  o = MergeOptions();
  o.response_curve.assign(100, 1.0f);
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("response_curve"), std::string::npos);
  const std::string m = ErrorOf([&] { MergeBrackets(SmallBrackets(), o); });
  EXPECT_NE(m.find("merge options: response_curve"), std::string::npos) << m;
  EXPECT_EQ(capture::ParseResponseModel("robertson", "--response"), ResponseModel::kRobertson);
  EXPECT_NE(ErrorOf([] { capture::ParseResponseModel("mitsunaga", "--response"); }).find("--response: unknown"),
            std::string::npos);
}

TEST(HdrMergeErrors, LoaderMissingTimesUnreadableAndCounts) {
  testing::ScratchDir dir("hdr_bad");
  cv::Mat grey(4, 8, CV_8UC3, cv::Scalar(90, 100, 110));
  const std::string a = dir / "a.png", b = dir / "b.png", garbage = dir / "garbage.png";
  ASSERT_TRUE(cv::imwrite(a, grey));
  ASSERT_TRUE(cv::imwrite(b, grey * 2));
  testing::WriteText(garbage, "not an image");
  // PNG without EXIF, no explicit times.
  std::string m = ErrorOf([&] { capture::LoadBrackets({a, b}, {}); });
  EXPECT_NE(m.find(a + ": no exposure time"), std::string::npos) << m;
  EXPECT_NE(m.find("EXIF"), std::string::npos) << m;
  // Unreadable and missing files.
  m = ErrorOf([&] { capture::LoadBrackets({a, garbage}, {0.01, 0.04}); });
  EXPECT_NE(m.find(garbage + ": cannot read image"), std::string::npos) << m;
  m = ErrorOf([&] { capture::LoadBrackets({a, dir / "missing.png"}, {0.01, 0.04}); });
  EXPECT_NE(m.find("missing.png: cannot read image"), std::string::npos) << m;
  // Counts and values of explicit times.
  m = ErrorOf([&] { capture::LoadBrackets({a, b}, {0.01}); });
  EXPECT_NE(m.find("exposure times: 1 given for 2 images"), std::string::npos) << m;
  m = ErrorOf([&] { capture::LoadBrackets({a, b}, {0.01, -1.0}); });
  EXPECT_NE(m.find(b + ": exposure time -1"), std::string::npos) << m;
  // A float image is not a bracket.
  const std::string exr = dir / "float.tiff";
  ASSERT_TRUE(cv::imwrite(exr, cv::Mat(4, 8, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5))));
  m = ErrorOf([&] { capture::ReadBracketImage(exr); });
  EXPECT_NE(m.find("float.tiff: expected an 8- or 16-bit"), std::string::npos) << m;
}

// --- EXIF (exiv2) -----------------------------------------------------------------------------------

TEST(HdrMergeExif, JpegRoundTripThroughLoader) {
  testing::ScratchDir dir("hdr_exif");
  const double times[2] = {1.0 / 250, 1.0 / 60};
  std::vector<std::string> paths;
  for (int i = 0; i < 2; ++i) {
    cv::Mat img(32, 64, CV_8UC3);
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) img.at<cv::Vec3b>(y, x) = cv::Vec3b(x * 2 + 40 * i, y * 4 + 40 * i, 100 + 40 * i);
    paths.push_back(dir / ("exif_" + std::to_string(i) + ".jpg"));
    ASSERT_TRUE(cv::imwrite(paths.back(), img));
    EXPECT_FALSE(capture::ReadExifExposure(paths.back()).has_exif);  // OpenCV writes none
    capture::ExifExposure e;
    e.exposure_time_s = times[i];
    e.f_number = 8.0;
    e.iso = 200;
    capture::WriteExifExposure(paths.back(), e);
    const capture::ExifExposure back = capture::ReadExifExposure(paths.back());
    EXPECT_TRUE(back.has_exif);
    EXPECT_DOUBLE_EQ(back.exposure_time_s, times[i]);  // stored as the rational 1/250, 1/60
    EXPECT_DOUBLE_EQ(back.f_number, 8.0);
    EXPECT_DOUBLE_EQ(back.iso, 200.0);
    EXPECT_EQ(back.error, "");
  }
  nlohmann::json report;
  const std::vector<Bracket> br = capture::LoadBrackets(paths, {}, 0, &report);
  ASSERT_EQ(br.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_DOUBLE_EQ(br[i].exposure_time_s, times[i]);
    EXPECT_DOUBLE_EQ(br[i].f_number, 8.0);
    EXPECT_DOUBLE_EQ(br[i].iso, 200.0);
    EXPECT_EQ(report["files"][i]["exposure_time_source"], "exif");
    EXPECT_EQ(br[i].image.bits, 8);
  }
  MergeOptions o;
  o.response = ResponseModel::kSrgb;
  const MergeResult r = MergeBrackets(br, o);
  EXPECT_TRUE(r.exposure_uses_aperture_iso);
  EXPECT_NEAR(r.exposure_factors[0], (1.0 / 250) * 2.0 / 64.0, 1e-12);
  // Explicit times win over EXIF; f-number and ISO still come from it.
  const std::vector<Bracket> over = capture::LoadBrackets(paths, {0.002, 0.008});
  EXPECT_DOUBLE_EQ(over[1].exposure_time_s, 0.008);
  EXPECT_DOUBLE_EQ(over[1].iso, 200.0);
  // A missing file is an error; a file without EXIF is not.
  EXPECT_NE(ErrorOf([&] { capture::ReadExifExposure(dir / "none.jpg"); }).find("none.jpg: no such file"), std::string::npos);
}

}  // namespace
}  // namespace skycal
