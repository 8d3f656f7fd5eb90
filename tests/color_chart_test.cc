// Colour-chart correction (capture/color_chart.h): CIEDE2000 against Sharma et al.'s test
// data, the published ColorChecker table against OpenCV's, a ColorChecker rendered into a
// real sky frame under a known 3x3 cast and recovered, the user-corner fallback, bad input
// (no chart, a clipped chart) and `skycal chart` / `capture --color-correction` end to end.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/mcc/ccm.hpp>

#include "run_binary.h"
#include "skycal/capture/color_chart.h"
#include "skycal/capture/color_difference.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/testing/synthetic_chart.h"
#include "test_util.h"

namespace skycal {
namespace {

using capture::Matrix3;
using capture::Rgb;
const std::string kRoot = SKYCAL_SOURCE_DIR;
testing::ProcessResult RunCli(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

// Sharma, Wu & Dalal (2005), Table 1: pairs 1, 7, 17, 25 (4 decimals published).
TEST(ColorDifference, Ciede2000MatchesSharmaTestData) {
  struct Pair {
    Rgb a, b;
    double de;
  };
  const Pair pairs[] = {{{50.0, 2.6772, -79.7751}, {50.0, 0.0, -82.7485}, 2.0425},
                        {{50.0, 0.0, 0.0}, {50.0, -1.0, 2.0}, 2.3669},
                        {{50.0, 2.5, 0.0}, {73.0, 25.0, -18.0}, 27.1492},
                        {{60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}, 1.2644}};
  for (const Pair& p : pairs) {
    EXPECT_NEAR(capture::DeltaE2000(p.a, p.b), p.de, 5e-5);
    EXPECT_NEAR(capture::DeltaE2000(p.b, p.a), p.de, 5e-5);  // symmetric
  }
  // Control: CIE76 of pair 1 is not CIEDE2000's (4.0011 vs 2.0425).
  EXPECT_NEAR(capture::DeltaE76(pairs[0].a, pairs[0].b), 4.0011, 1e-4);
  // White: L* 100, a* = b* = 0.
  const Rgb white = capture::LinearRec709ToLab({1.0, 1.0, 1.0});
  EXPECT_NEAR(white[0], 100.0, 1e-3);
  EXPECT_NEAR(white[1], 0.0, 0.02);
  EXPECT_NEAR(white[2], 0.0, 0.02);
}

// Our table (X-Rite's sRGB) against OpenCV ccm's own (BabelColor's ColorChecker 2005 CIELAB,
// D50, adapted to D65 by OpenCV): two measurement sets of the same physical chart.
TEST(ColorChart, PublishedTableAgreesWithOpenCvs) {
  const auto& ref = capture::ColorCheckerLinearRec709();
  cv::Mat src(24, 1, CV_64FC3);
  for (int i = 0; i < 24; ++i) src.at<cv::Vec3d>(i) = cv::Vec3d(ref[i][0], ref[i][1], ref[i][2]);
  cv::ccm::ColorCorrectionModel model(src, cv::ccm::COLORCHECKER_Macbeth);
  model.setLinear(cv::ccm::LINEARIZATION_IDENTITY);
  model.run();
  const cv::Mat dst = model.get_dst_rgbl();  // OpenCV's patches, linear sRGB
  ASSERT_EQ(dst.total(), 24u);
  double sum = 0.0, worst = 0.0;
  for (int i = 0; i < 24; ++i) {
    const cv::Vec3d d = dst.at<cv::Vec3d>(i);
    const double de = capture::DeltaE2000(capture::LinearRec709ToLab(ref[i]), capture::LinearRec709ToLab({d[0], d[1], d[2]}));
    sum += de;
    worst = std::max(worst, de);
    EXPECT_LT(de, 6.0) << "patch " << i + 1 << " " << capture::ColorCheckerPatchName(i);
  }
  std::printf("published sRGB table vs OpenCV's ColorChecker 2005: mean CIEDE2000 %.2f, max %.2f\n", sum / 24, worst);
  EXPECT_LT(sum / 24, 2.5);
}

// A known camera colour cast: cross-talk between channels and a warm white balance.
const Matrix3 kCast = {0.82, 0.16, 0.04, 0.06, 0.87, 0.09, 0.01, 0.14, 0.64};

struct ChartScene {
  ImageRGB frame;                     // the real sky with a chart, through the cast
  ImageRGB truth;                     // the same without the cast
  std::array<double, 8> corners{};
};

// The real frames come from datasets/fetch_real_skies.sh (run by scripts/test.sh); without
// them these tests skip, as real_sky_test does, rather than fail on a download.
#define SKIP_WITHOUT_REAL_SKY()                                                            \
  if (!std::filesystem::exists(kRoot + "/datasets/real/sky.exr"))                          \
  GTEST_SKIP() << "datasets/real/sky.exr absent: run datasets/fetch_real_skies.sh"

// datasets/real/sky.exr (512x256) with a chart on the ground, lit at 40% of the sky's
// median luminance, 1% multiplicative noise, then the cast.
ChartScene MakeScene() {
  ChartScene s;
  s.truth = ReadExrRGB(kRoot + "/datasets/real/sky.exr").image;
  std::vector<float> y;
  for (size_t i = 0; i < s.truth.pixels.size(); i += 3) y.push_back(0.2126f * s.truth.pixels[i] + 0.7152f * s.truth.pixels[i + 1] + 0.0722f * s.truth.pixels[i + 2]);
  std::nth_element(y.begin(), y.begin() + y.size() / 2, y.end());
  s.corners = testing::RenderChart(&s.truth, {300.0, 170.0, 5.0, 0.4 * y[y.size() / 2] / 0.89});
  std::mt19937 rng(14);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (float& v : s.truth.pixels) v = std::max(0.0f, v * (1.0f + noise(rng)));
  s.frame = s.truth;
  capture::ApplyColorCorrection(kCast, &s.frame);
  return s;
}

// Every second pixel of every second row: the no-chart cases need no more (mcc's search
// time grows with the pixels, and it runs at every exposure of the ladder).
ImageRGB Half(const ImageRGB& img) {
  ImageRGB h(img.width / 2, img.height / 2);
  for (int y = 0; y < h.height; ++y)
    for (int x = 0; x < h.width; ++x)
      for (int c = 0; c < 3; ++c) h.at(x, y, c) = img.at(2 * x, 2 * y, c);
  return h;
}

capture::ChartImage AsChartImage(const ImageRGB& img, const std::string& name) {
  return {name, img, std::vector<uint8_t>(static_cast<size_t>(img.width) * img.height, 0)};
}

double Mean(const std::array<double, 24>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); }

void ExpectCastRecovered(const capture::ColorCorrection& cc) {
  // Mean CIEDE2000 < 1 after (the issue's target), and the cast was a real one before.
  std::printf("chart CIEDE2000: before mean %.2f max %.2f, after mean %.3f max %.3f\n", Mean(cc.delta_e_before),
              *std::max_element(cc.delta_e_before.begin(), cc.delta_e_before.end()), Mean(cc.delta_e_after),
              *std::max_element(cc.delta_e_after.begin(), cc.delta_e_after.end()));
  EXPECT_GT(Mean(cc.delta_e_before), 5.0);
  EXPECT_LT(Mean(cc.delta_e_after), 1.0);
  // M * cast = k I: the cast itself, not only the chart, is undone (3%: the chart's 24
  // colours under 1% noise pin the 9 entries to about that).
  const Matrix3 mc = capture::MultiplyMatrices(cc.matrix, kCast);
  const double k = (mc[0] + mc[4] + mc[8]) / 3.0;
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(mc[i] / k, i % 4 == 0 ? 1.0 : 0.0, 0.03) << "entry " << i;
}

TEST(ColorChart, CastInARealSkyFrameIsRecoveredByDetection) {
  SKIP_WITHOUT_REAL_SKY();
  const ChartScene s = MakeScene();
  const capture::ChartDetection d = capture::FindColorChecker(AsChartImage(s.frame, "scene"), {});
  EXPECT_EQ(d.method, "mcc");
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(d.corners[k], s.corners[k], 6.0) << "corner coordinate " << k;  // half a patch (12.5 px); measured <= 4.8
  const capture::ColorCorrection cc = capture::FitColorCorrection(d.patches);
  ExpectCastRecovered(cc);
  // The sky, corrected, is the sky without the cast up to the one scale (median |error| < 1%).
  ImageRGB fixed = s.frame;
  capture::ApplyColorCorrection(cc.matrix, &fixed);
  const Matrix3 mc = capture::MultiplyMatrices(cc.matrix, kCast);
  const double k = (mc[0] + mc[4] + mc[8]) / 3.0;
  std::vector<double> err;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < fixed.width; ++x)
      for (int c = 0; c < 3; ++c) err.push_back(std::abs(fixed.at(x, y, c) / k / s.truth.at(x, y, c) - 1.0));
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  EXPECT_LT(err[err.size() / 2], 0.01);
}

TEST(ColorChart, UserCornersAreTheFallback) {
  SKIP_WITHOUT_REAL_SKY();
  const ChartScene s = MakeScene();
  capture::ChartOptions o;
  o.corners = s.corners;
  const capture::ChartDetection d = capture::FindColorChecker(AsChartImage(s.frame, "scene"), o);
  EXPECT_EQ(d.method, "user corners");
  ExpectCastRecovered(capture::FitColorCorrection(d.patches));
  // Corners in the wrong order (rotated by one): refused, not fitted to the wrong patches.
  std::array<double, 8> rotated{};
  for (int k = 0; k < 8; ++k) rotated[k] = s.corners[(k + 2) % 8];
  o.corners = rotated;
  EXPECT_THROW(capture::FindColorChecker(AsChartImage(s.frame, "scene"), o), Error);
}

TEST(ColorChart, NoChartIsAClearError) {
  SKIP_WITHOUT_REAL_SKY();
  const ImageRGB sky = Half(ReadExrRGB(kRoot + "/datasets/real/sky.exr").image);
  try {
    capture::FindColorChecker(AsChartImage(sky, "sky.exr"), {});
    FAIL() << "a sky without a chart gave a chart";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sky.exr: no ColorChecker 24 chart found"), std::string::npos) << e.what();
  }
}

// 8-bit PNG of a chart whose white patches are at full scale: refused naming the patch.
TEST(ColorChart, ClippedChartIsRefusedNamingThePatch) {
  testing::ScratchDir dir("color_chart_clip");
  ImageRGB img(160, 112);
  for (float& v : img.pixels) v = 0.2f;
  const auto corners = testing::RenderChart(&img, {20.0, 20.0, 7.0, 1.2});  // white 9.5 at 1.08 -> 255; the next brightest (yellow's R) 0.96
  cv::Mat bgr(img.height, img.width, CV_8UC3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c)
        bgr.at<cv::Vec3b>(y, x)[2 - c] = static_cast<uint8_t>(std::lround(255.0 * std::min(1.0f, img.at(x, y, c))));
  const std::string png = dir / "clipped.png";
  ASSERT_TRUE(cv::imwrite(png, bgr));
  capture::ChartOptions o;
  o.corners = corners;
  for (const bool detect : {false, true}) {
    try {
      capture::FindColorChecker(capture::LoadChartImage(png, {}), detect ? capture::ChartOptions{} : o);
      FAIL() << "a clipped chart was fitted";
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("clipped.png"), std::string::npos) << m;
      // Detected or not (mcc may not find a chart with a blown-out row), the message is about this file.
      if (!detect) {
        EXPECT_NE(m.find("patch 19 (white 9.5) is clipped: 100%"), std::string::npos) << m;
      }
      std::printf("%s: %s\n", detect ? "detected" : "corners", m.c_str());
    }
  }
}

// skycal chart writes the correction; capture --color-correction applies it and stores it.
TEST(ColorChart, ChartVerbAndCaptureThroughTheBinary) {
  SKIP_WITHOUT_REAL_SKY();
  testing::ScratchDir dir("color_chart_cli");
  const ChartScene s = MakeScene();
  WriteExrRGB(dir / "chart.exr", s.frame, {});
  const std::string cc_json = dir / "cc.json";
  auto r = RunCli("chart --image " + (dir / "chart.exr") + " --out " + cc_json + " --label no-nd --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(ReadFile(cc_json));
  EXPECT_LT(j["delta_e2000"]["after"]["mean"].get<double>(), 1.0);
  EXPECT_EQ(j["label"], "no-nd");
  // Not found / bad options: exit 1, the file named, nothing written.
  const ImageRGB plain = Half(Half(ReadExrRGB(kRoot + "/datasets/real/sky.exr").image));
  WriteExrRGB(dir / "plain.exr", plain, {});
  r = RunCli("chart --image " + (dir / "plain.exr") + " --out " + (dir / "none.json"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("plain.exr: no ColorChecker 24 chart found"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "none.json"));
  r = RunCli("chart --image " + (dir / "chart.exr") + " --out " + (dir / "none.json") + " --chart-corners 1,2,3");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--chart-corners: expected 8 numbers"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "none.json"));
}


// capture --color-correction: the frame is the matrix times the uncorrected frame, and the
// correction is in its metadata; contradictory flags are refused.
TEST(ColorChart, CaptureAppliesAndStoresTheCorrection) {
  testing::ScratchDir dir("color_chart_capture");
  // Two 8-bit brackets (64x32, linear codes 1 EV apart) of a smooth coloured gradient.
  std::vector<std::string> brackets;
  for (int b = 0; b < 2; ++b) {
    cv::Mat bgr(32, 64, CV_8UC3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x) {
        const double base[3] = {20.0 + 1.5 * x, 30.0 + 2.0 * y, 60.0 + 0.5 * (x + y)};
        const double star = (x == 20 && y == 8) ? 3.0 : 1.0;  // one point source, for --remove-stars
        for (int c = 0; c < 3; ++c) bgr.at<cv::Vec3b>(y, x)[2 - c] = static_cast<uint8_t>(std::min(255.0, star * base[c] * (1 << b) * 0.6));
      }
    brackets.push_back(dir / ("b" + std::to_string(b) + ".png"));
    ASSERT_TRUE(cv::imwrite(brackets.back(), bgr));
  }
  const Matrix3 m = {1.2, -0.1, -0.1, -0.05, 1.1, -0.05, 0.0, -0.2, 1.2};
  const std::string cc = dir / "cc.json";
  WriteFileAtomically(cc, nlohmann::json{{"format", "skycal.color_correction"}, {"version", 1}, {"matrix", m}, {"label", "nd"}}.dump());
  const std::string base = "capture --brackets " + brackets[0] + " " + brackets[1] +
                           " --exposure-times 0.01,0.02 --response linear --lens latlong --size 64x32 --out ";
  auto r = RunCli(base + (dir / "plain.exr"));
  ASSERT_EQ(r.rc, 0) << r.err;
  r = RunCli(base + (dir / "corrected.exr") + " --color-correction " + cc);
  ASSERT_EQ(r.rc, 0) << r.err;
  const ExrRGB plain = ReadExrRGB(dir / "plain.exr"), corrected = ReadExrRGB(dir / "corrected.exr");
  for (size_t i = 0; i < plain.image.pixels.size(); i += 3) {
    const Rgb want = capture::Apply(m, {plain.image.pixels[i], plain.image.pixels[i + 1], plain.image.pixels[i + 2]});
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(corrected.image.pixels[i + c], want[c], 1e-5 * std::abs(want[c]) + 1e-9);
  }
  ASSERT_TRUE(corrected.attributes.strings.count("skycalColorCorrection"));
  EXPECT_EQ(nlohmann::json::parse(corrected.attributes.strings.at("skycalColorCorrection"))["label"], "nd");
  EXPECT_FALSE(plain.attributes.strings.count("skycalColorCorrection"));
  // --remove-stars: the point source is counted and masked (mask.stars), the rest untouched.
  r = RunCli(base + (dir / "stars.exr") + " --remove-stars --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["stars"]["stars_removed"], 1);
  int w = 0, h = 0;
  const std::vector<float> star_mask = ReadExrChannel(dir / "stars.exr", "mask.stars", &w, &h);
  const ExrRGB starless = ReadExrRGB(dir / "stars.exr");
  int masked = 0;
  for (size_t i = 0; i < star_mask.size(); ++i) {
    masked += star_mask[i] == 1.0f;
    if (star_mask[i] == 0.0f) {
      for (int c = 0; c < 3; ++c) ASSERT_EQ(starless.image.pixels[3 * i + c], plain.image.pixels[3 * i + c]);
    }
  }
  EXPECT_GE(masked, 1);
  EXPECT_LE(masked, 16);
  // Bad input: exit 1, named, nothing written.
  const std::string out = dir / "bad.exr";
  WriteFileAtomically(dir / "bad.json", R"({"format": "skycal.color_correction", "matrix": [1, 0, 0]})");
  r = RunCli(base + out + " --color-correction " + (dir / "bad.json"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("bad.json: field 'matrix': expected 9 numbers"), std::string::npos) << r.err;
  r = RunCli(base + out + " --color-correction " + cc + " --input-colorspace ACEScg");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--color-correction with --input-colorspace ACEScg"), std::string::npos) << r.err;
  r = RunCli(base + out + " --star-sigma 4");  // a star option without --remove-stars does nothing: refused
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("only with --remove-stars"), std::string::npos) << r.err;
  r = RunCli(base + out + " --chart " + brackets[0]);  // a gradient, no chart
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("b0.png: no ColorChecker 24 chart found"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace skycal
