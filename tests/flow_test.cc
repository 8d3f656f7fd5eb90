// skycal flow: motion vectors between time-lapse frames. A cloud render shifted by a known
// amount (whole pixels, wrapping in longitude) is the later frame: the end-point error of
// the vectors against that shift, the 8-bit encoding against the float one, a frame
// against itself as the control, and frames of two sizes refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "flow_verb.h"
#include "run_binary.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/optical_flow.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "test_util.h"
#include "skycal/capture/zenith_cap.h"

namespace skycal {
namespace {

constexpr int kDx = 6, kDy = 2;  // the clouds' motion, full-resolution pixels

// b(x, y) = a(x - dx, y - dy): longitude wraps (period width - 1), rows clamp.
ImageRGB Shifted(const ImageRGB& a, int dx, int dy) {
  ImageRGB b(a.width, a.height);
  const int period = a.width - 1;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const int sx = (((x - dx) % period) + period) % period, sy = std::clamp(y - dy, 0, a.height - 1);
      for (int c = 0; c < 3; ++c) b.at(x, y, c) = a.at(sx, sy, c);
    }
  return b;
}

struct Epe {
  double median = 0.0, mean = 0.0, seam_mean = 0.0;
};

// End-point error (full-resolution pixels) of forward vectors in texture space over the
// sky rows from 14 deg (where the clouds are) to 40 deg elevation of a qw x qh field. Above
// 40 deg the flow comes from the zenith cap's polar view (zenith_cap.h), where a lat-long
// shift is a rotation plus a radial stretch of the image — and at this render's time the
// sky up there is clear, a smooth gradient whose motion the frames cannot pin down (any
// vector along its isophotes matches). The cap is measured on clouds moved by the wind,
// with a ground truth, in flow_wind_test.cc.
Epe EndPointError(const std::vector<float>& u, const std::vector<float>& v, int qw, int qh, int w, int h) {
  std::vector<double> e;
  double seam = 0.0;
  int seam_n = 0;
  for (int y = qh * 9 / 32; y < qh * 4 / 9; ++y)
    for (int x = 0; x < qw; ++x) {
      const size_t i = static_cast<size_t>(y) * qw + x;
      const double d = std::hypot(u[i] * (w - 1) - kDx, v[i] * (h - 1) - kDy);
      e.push_back(d);
      if (x < 2 || x >= qw - 2) seam += d, ++seam_n;
    }
  Epe out;
  double sum = 0.0;
  for (double d : e) sum += d;
  out.mean = sum / e.size();
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  out.median = e[e.size() / 2];
  out.seam_mean = seam / seam_n;
  return out;
}

TEST(Flow, CloudsMovedByAKnownShiftAreRecovered) {
  testing::ScratchDir dir("flow");
  const std::string a_path = dir / "a.exr", b_path = dir / "b.exr";
  const auto r = testing::RunSkycal(SKYCAL_BINARY, "render --preset " + std::string(SKYCAL_SOURCE_DIR) +
                                                       "/datasets/presets/default_cloudy.json --clouds --sun-elevation 25 "
                                                       "--sun-azimuth 30 --size 256x128 --out " + a_path);
  ASSERT_EQ(r.rc, 0) << r.err;
  capture::LatLongFrame a = capture::ReadLatLongFrame(a_path);
  capture::LatLongFrame b = a;
  b.radiance = Shifted(a.radiance, kDx, kDy);
  capture::WriteLatLongFrame(b_path, b);

  cli::FlowOptions o;
  o.a = a_path;
  o.b = b_path;
  o.out = dir / "v.exr";
  const nlohmann::json summary = cli::RunFlowImpl(o);
  const int qw = summary["width"], qh = summary["height"];
  EXPECT_EQ(qw, 64);
  EXPECT_EQ(qh, 32);
  const ExrRGB v = ReadExrRGB(o.out);
  std::vector<float> fu(qw * qh), fv(qw * qh);
  for (int i = 0; i < qw * qh; ++i) fu[i] = v.image.pixels[3 * i], fv[i] = v.image.pixels[3 * i + 1];
  const Epe epe = EndPointError(fu, fv, qw, qh, 256, 128);
  std::cout << "[flow] forward end-point error over the sky at 14..40 deg: median " << epe.median << " px, mean "
            << epe.mean << " px, at the seam " << epe.seam_mean << " px (shift " << kDx << ", " << kDy << " px)\n";
  // Measured 0.020 / 0.019 / 0.018 px (DIS on 8-bit log luminance; whole-pixel shifts; over
  // the whole sky above 14 deg before the zenith cap 0.015 / 0.017 / 0.019 px):
  // bounds with a margin of ~5x.
  EXPECT_LT(epe.median, 0.1);
  EXPECT_LT(epe.mean, 0.3);
  EXPECT_LT(epe.seam_mean, 0.3);  // the longitude wraps: the seam moves like the rest

  // Backward vectors: minus the forward ones.
  int wb = 0, hb = 0;
  const std::vector<float> bu = ReadExrChannel(o.out, "backward.u", &wb, &hb);
  std::vector<float> neg_u(bu.size()), neg_v(bu.size());
  const std::vector<float> bv = ReadExrChannel(o.out, "backward.v", &wb, &hb);
  for (size_t i = 0; i < bu.size(); ++i) neg_u[i] = -bu[i], neg_v[i] = -bv[i];
  const Epe back = EndPointError(neg_u, neg_v, qw, qh, 256, 128);
  std::cout << "[flow] backward: median " << back.median << " px, mean " << back.mean << " px\n";
  EXPECT_LT(back.median, 0.1);

  // The 8-bit file decodes through the sidecar to the float vectors within half a code.
  const nlohmann::json meta = nlohmann::json::parse(std::ifstream(dir / "v.json"));
  const cv::Mat png = cv::imread(dir / "v.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.type(), CV_8UC4);
  const double lo = meta["components"][0]["min"], hi = meta["components"][0]["max"];
  double worst = 0.0;
  for (int y = 0; y < qh; ++y)
    for (int x = 0; x < qw; ++x) {
      const double decoded = lo + (hi - lo) * png.at<cv::Vec4b>(y, x)[2] / 255.0;  // R (BGRA in OpenCV)
      worst = std::max(worst, std::abs(decoded - fu[static_cast<size_t>(y) * qw + x]));
    }
  EXPECT_LE(worst, 0.5 * (hi - lo) / 255.0 + 1e-7);

  // Control: a frame against itself has no motion (the vectors ~0), so the same check fails.
  const std::vector<float> still = capture::DenseFlow(a.radiance, a.radiance);
  std::vector<float> su(qw * qh), sv(qw * qh);
  for (int y = 0; y < qh; ++y)
    for (int x = 0; x < qw; ++x) {
      const size_t f = 2 * (static_cast<size_t>(4 * y + 2) * 256 + 4 * x + 2), q = static_cast<size_t>(y) * qw + x;
      su[q] = still[f] / 255.0f;
      sv[q] = still[f + 1] / 127.0f;
    }
  const Epe control = EndPointError(su, sv, qw, qh, 256, 128);
  EXPECT_GT(control.median, 5.0);
}

// The zenith cap's polar view: a direction's polar position maps back to it; the zenith sits
// at the centre; at oversample 1 a lat-long row's step in elevation is one polar pixel
// radially, at any azimuth; LatLongDirection inverts latlong::PixelPosition.
TEST(ZenithCap, PolarViewRoundTripsAndKeepsTheRowsAngle) {
  const capture::ZenithCap cap(256, 128, 60.0);
  EXPECT_EQ(cap.size, 2 * static_cast<int>(std::ceil(60.0 / 180.0 * 127)) + 1);
  const std::array<double, 2> z = cap.PolarPosition({0.0, 1.0, 0.0});
  EXPECT_DOUBLE_EQ(z[0], cap.centre);
  EXPECT_DOUBLE_EQ(z[1], cap.centre);
  double worst = 0.0, worst_row = 0.0;
  for (int y = 1; y < 40; y += 3)
    for (int x = 0; x < 255; x += 17) {
      const latlong::Vec3d d = latlong::PixelDirection(x, y, 256, 128), e = latlong::PixelDirection(x, y + 1, 256, 128);
      const std::array<double, 2> q = cap.PolarPosition(d), qe = cap.PolarPosition(e);
      const latlong::Vec3d back = cap.PolarDirection(q[0], q[1]);
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(back[c] - d[c]));
      worst_row = std::max(worst_row, std::abs(std::hypot(qe[0] - q[0], qe[1] - q[1]) - 1.0));
      const latlong::Vec3d ll = capture::LatLongDirection(x + 0.25, y + 0.5, 256, 128);
      const std::array<double, 2> p = latlong::PixelPosition(ll, 256, 128);
      EXPECT_NEAR(p[0], x + 0.25, 1e-9);
      EXPECT_NEAR(p[1], y + 0.5, 1e-9);
    }
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(worst_row, 1e-9);
  // Control: at oversample 3 the same row step is 3 polar pixels, not 1.
  const capture::ZenithCap fine(256, 128, 60.0, 3.0);
  const std::array<double, 2> a = fine.PolarPosition(latlong::PixelDirection(5, 10, 256, 128)),
                              b = fine.PolarPosition(latlong::PixelDirection(5, 11, 256, 128));
  EXPECT_NEAR(std::hypot(b[0] - a[0], b[1] - a[1]), 3.0, 1e-9);
}

TEST(Flow, FramesOfTwoSizesAreRefused) {
  testing::ScratchDir dir("flow-bad");
  capture::LatLongFrame f;
  f.radiance = ImageRGB(64, 32);
  for (float& v : f.radiance.pixels) v = 1.0f;
  capture::WriteLatLongFrame(dir / "a.exr", f);
  f.radiance = ImageRGB(128, 64);
  for (float& v : f.radiance.pixels) v = 1.0f;
  capture::WriteLatLongFrame(dir / "b.exr", f);
  const auto r = testing::RunSkycal(SKYCAL_BINARY, "flow " + (dir / "a.exr") + " " + (dir / "b.exr") + " --out " + (dir / "v.exr"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("b.exr: frame is 128x64, but " + (dir / "a.exr") + " is 64x32"), std::string::npos) << r.err;
  EXPECT_EQ(dir.CountEntries(), 2);  // nothing written
  const auto one = testing::RunSkycal(SKYCAL_BINARY, "flow " + (dir / "a.exr") + " --out " + (dir / "v.exr"));
  EXPECT_EQ(one.rc, 1);
  EXPECT_NE(one.err.find("expected two frames"), std::string::npos) << one.err;
}

TEST(FlowOptions, IsValidNamesTheFieldAndItsValue) {
  capture::FlowOptions o;
  o.a = "a.exr";
  o.b = "b.exr";
  o.out = "v.exr";
  o.scale = 17;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FlowOptions::scale = 17 (expected an integer in [1, 16]: 1 / scale of the frames' size)");
}

}  // namespace
}  // namespace skycal
