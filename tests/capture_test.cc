// `skycal capture` end to end: a real lat-long sky photographed by a simulated fisheye
// camera (7 noisy 8-bit brackets with an sRGB camera curve) goes back to a lat-long frame
// with masks and metadata; bad input is refused without output.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "capture_verb.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "synthetic_brackets.h"
#include "synthetic_fisheye.h"
#include "test_util.h"

namespace skycal {
namespace {

struct Scene {
  ImageRGB latlong;                // the truth, 1024x512
  std::vector<std::string> paths;  // bracket PNGs of the up-looking fisheye
  // Merged radiance = scale * scene radiance: the simulated camera records gain * L * k with
  // k = t ISO/100 / N^2, and PNG brackets carry no f-number/ISO, so the merge divides by t.
  double scale = 0.0;
  std::vector<double> times;
};

Scene MakeScene(const testing::ScratchDir& dir) {
  Scene s;
  std::string source;
  s.latlong = synthetic::LoadBracketScene(1024, 512, &source);
  capture::RigCamera cam;
  cam.lens = synthetic::InscribedLens(capture::LensModel::kEquisolid, 180.0, 800);
  cam.width = cam.height = 800;
  cam.rotation = capture::RotationFromYawPitchRollDeg(0.0, 90.0, 0.0);
  const ImageRGB view = synthetic::RenderCameraView(s.latlong, cam);
  synthetic::BracketSpec spec;
  spec.curve = synthetic::CameraCurve::kSrgb;
  const synthetic::SyntheticBrackets b = synthetic::MakeSyntheticBrackets(view, spec);
  s.paths = synthetic::WriteBracketsPng(b, dir.path().string());
  s.scale = b.gain * (spec.iso / 100.0) / (spec.f_number * spec.f_number);
  s.times = spec.exposure_times_s;
  return s;
}

cli::CaptureOptions BaseOptions(const Scene& s, const std::string& out) {
  cli::CaptureOptions o;
  o.brackets = s.paths;
  o.exposure_times_s = s.times;
  o.merge.response = capture::ResponseModel::kSrgb;
  o.lens.model = capture::LensModel::kEquisolid;
  o.lens.fov_deg = 180.0;
  o.camera_ypr_deg = {0.0, 90.0, 0.0};
  o.width = 512;
  o.height = 256;
  o.out = out;
  return o;
}

TEST(Capture, BracketsOfAFisheyeBecomeTheLatLong) {
  testing::ScratchDir dir("capture");
  const Scene s = MakeScene(dir);
  cli::CaptureOptions o = BaseOptions(s, dir / "frame.exr");
  o.time_iso = "2024-06-21T19:30:00+02:00";
  o.latitude_deg = 45.43;
  o.longitude_deg = 12.33;
  const nlohmann::json j = cli::RunCaptureImpl(o);
  EXPECT_GT(j["valid_pixels"].get<long long>(), 40000);
  for (const char* stage : {"merge_ms", "colour_ms", "unwrap_ms", "sun_ms", "write_ms"}) EXPECT_TRUE(j["stages"].contains(stage));

  const capture::LatLongFrame f = capture::ReadLatLongFrame(dir / "frame.exr");
  ASSERT_TRUE(f.sun_direction.has_value());  // from SPA
  EXPECT_GT((*f.sun_direction)[1], 0.0);     // 19:30 CEST in Venice at midsummer: still up
  int w = 0, h = 0;
  const std::vector<float> valid = ReadExrChannel(dir / "frame.exr", "mask.valid", &w, &h);
  const std::vector<float> below = ReadExrChannel(dir / "frame.exr", "mask.belowHorizon", &w, &h);
  const std::vector<float> cloud = ReadExrChannel(dir / "frame.exr", "mask.cloud", &w, &h);
  EXPECT_TRUE(std::all_of(cloud.begin(), cloud.end(), [](float p) { return p >= 0.0f && p <= 1.0f; }));
  ASSERT_EQ(w, 512);
  // Against the truth (point-sampled at the frame's nodes): relative luminance error over
  // valid sky pixels above 5 deg (the fisheye's edge is at the horizon, where the image
  // circle is sampled most coarsely) and away from the sun.
  std::vector<double> errors;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const auto d = latlong::PixelDirection(x, y, w, h);
      if (latlong::Latitude(y, h) <= 0.0) {
        EXPECT_EQ(below[i], 1.0f);
        continue;
      }
      if (valid[i] < 0.5f || latlong::ElevationDeg(d) < 5.0) continue;
      float truth[3];
      synthetic::SampleLatLong(s.latlong, d, truth);
      const double lt = s.scale * (0.2126 * truth[0] + 0.7152 * truth[1] + 0.0722 * truth[2]);
      const double lg = 0.2126 * f.radiance.at(x, y, 0) + 0.7152 * f.radiance.at(x, y, 1) + 0.0722 * f.radiance.at(x, y, 2);
      if (lt > 0.0) errors.push_back(std::abs(lg / lt - 1.0));
    }
  }
  ASSERT_GT(errors.size(), 20000u);
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], p95 = errors[errors.size() * 95 / 100];
  std::cout << "[capture] " << errors.size() << " px, median rel " << median << ", p95 " << p95 << "\n";
  // Tolerances: merge noise ~1% median / 3% p95 (hdr_merge_test) plus unwrap filtering of a
  // 1024x512 source seen through an 800 px fisheye (sharp cloud and building edges).
  EXPECT_LT(median, 0.03);
  EXPECT_LT(p95, 0.15);
}

TEST(Capture, BadInputIsRefusedAndNothingIsWritten) {
  testing::ScratchDir dir("capture-bad");
  const Scene s = MakeScene(dir);
  {
    cv::Mat small(10, 10, CV_8UC3, cv::Scalar(10, 20, 30));
    cv::imwrite(dir / "small.png", small);
  }
  const int before = dir.CountEntries();
  auto expect = [&](cli::CaptureOptions o, const std::string& needle) {
    try {
      cli::RunCaptureImpl(o);
      ADD_FAILURE() << "accepted; expected '" << needle << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_EQ(dir.CountEntries(), before) << needle;
  };
  const std::string out = dir / "frame.exr";
  cli::CaptureOptions o = BaseOptions(s, out);
  o.brackets = {s.paths[0]};
  o.exposure_times_s = {s.times[0]};
  expect(o, "at least two exposures");
  o = BaseOptions(s, out);
  o.exposure_times_s.clear();  // PNGs carry no EXIF
  expect(o, "ExposureTime");
  o = BaseOptions(s, out);
  o.brackets[2] = dir / "missing.png";
  expect(o, "missing.png");
  o = BaseOptions(s, out);
  o.brackets[3] = dir / "small.png";
  expect(o, "small.png");
  o = BaseOptions(s, out);
  o.input_colorspace = "Kodachrome";
  expect(o, "Kodachrome");
  o = BaseOptions(s, out);
  o.lens.radius_px = 5000.0;
  o.lens_radius_given = true;
  expect(o, "radius");
  o = BaseOptions(s, out);
  o.time_iso = "2024-13-01T10:00:00Z";
  o.latitude_deg = 10.0;
  o.longitude_deg = 10.0;
  expect(o, "month");
  o = BaseOptions(s, out);
  o.time_iso = "2024-06-01T10:00:00Z";
  o.latitude_deg = 95.0;
  o.longitude_deg = 10.0;
  expect(o, "latitude");
}

}  // namespace
}  // namespace skycal
