// `skycal capture` end to end: a real lat-long sky photographed by a simulated fisheye
// camera (7 noisy 8-bit brackets with an sRGB camera curve) goes back to a lat-long frame
// with masks and metadata; bad input is refused without output.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>

#include "capture_verb.h"
#include "skycal/capture/capture_pipeline.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "run_binary.h"
#include "skycal/testing/synthetic_brackets.h"
#include "skycal/testing/synthetic_fisheye.h"
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
  o.camera_ypr_deg = std::array<double, 3>{0.0, 90.0, 0.0};
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
  expect(o, "merged from '" + o.brackets[0] + "' and the other brackets");  // the lens's image is named
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

// Lat-long brackets (an equirectangular camera, or a panorama already stitched) through the
// binary: with --lens latlong and no --camera-rotation the frame is the input's own lat-long
// (the old default, the fisheye's 0,90,0, turned it 90 degrees: ~80% error); contradictory
// lens flags are refused, naming them, with nothing written.
TEST(Capture, LatLongBracketsKeepTheirOrientationThroughTheBinary) {
  testing::ScratchDir dir("capture-latlong");
  std::string source;
  const ImageRGB scene = synthetic::LoadBracketScene(256, 128, &source);
  synthetic::BracketSpec spec;
  spec.curve = synthetic::CameraCurve::kSrgb;
  const synthetic::SyntheticBrackets b = synthetic::MakeSyntheticBrackets(scene, spec);
  const std::vector<std::string> paths = synthetic::WriteBracketsPng(b, dir.path().string());
  std::string args = "capture --brackets";
  for (const auto& p : paths) args += " " + p;
  args += " --exposure-times ";
  for (size_t i = 0; i < spec.exposure_times_s.size(); ++i) args += (i ? "," : "") + std::to_string(spec.exposure_times_s[i]);
  args += " --response srgb --lens latlong --size 256x128";
  const double scale = (spec.iso / 100.0) / (spec.f_number * spec.f_number);  // PNGs: the merge divides by t only
  // Median relative error of a written frame against the scene, pixels well measured only.
  auto median_error = [&](const std::string& path) {
    const ExrRGB frame = ReadExrRGB(path);
    EXPECT_EQ(frame.image.width, 256);
    std::vector<double> rel;
    for (size_t p = 0; p < b.truth_well.size(); ++p) {
      if (!b.truth_well[p]) continue;
      for (int c = 0; c < 3; ++c) {
        const double truth = b.truth.pixels[3 * p + c] * scale;
        rel.push_back(std::fabs(frame.image.pixels[3 * p + c] - truth) / truth);
      }
    }
    EXPECT_GT(rel.size(), 3u * 256 * 128 / 2);
    return synthetic::Quantile(rel, 0.5);
  };
  const std::string out = dir / "frame.exr";
  const auto r = testing::RunSkycal(SKYCAL_BINARY, args + " --out " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.err.find("camera rotation = identity"), std::string::npos) << r.err;
  const double err_default = median_error(out);
  std::printf("[measured] latlong default rotation: median rel error %.4f\n", err_default);
  // sRGB decode of noisy 8-bit codes and the unwrap's bilinear resampling at the same size.
  EXPECT_LT(err_default, 0.03);
  // Control: the old default (looking up) turns the panorama, and the error shows it.
  const std::string turned = dir / "turned.exr";
  ASSERT_EQ(testing::RunSkycal(SKYCAL_BINARY, args + " --camera-rotation 0,90,0 --out " + turned).rc, 0);
  const double err_turned = median_error(turned);
  std::printf("[measured] latlong with --camera-rotation 0,90,0: median rel error %.4f\n", err_turned);
  EXPECT_GT(err_turned, 10.0 * err_default);
  // Contradictions: refused (exit 1) naming the flag, nothing written.
  const int before = dir.CountEntries();
  for (const auto& [extra, needle] : std::vector<std::pair<std::string, std::string>>{
           {"--lens-fov-deg 180", "--lens-fov-deg"},
           {"--lens-center 10,10 --lens-radius 50", "--lens-center, --lens-radius"},
           {"--vignetting 0.1,0,0", "--vignetting"},
           {"--kb-k 0,0,0,0", "--kb-k"}}) {
    const auto bad = testing::RunSkycal(SKYCAL_BINARY, args + " " + extra + " --out " + (dir / "bad.exr"));
    EXPECT_EQ(bad.rc, 1) << extra;
    EXPECT_NE(bad.err.find(needle), std::string::npos) << bad.err;
    EXPECT_NE(bad.err.find("lat-long input has none"), std::string::npos) << bad.err;
  }
  const auto kb = testing::RunSkycal(SKYCAL_BINARY, "capture --brackets " + paths[0] + " " + paths[1] +
                                                        " --exposure-times 1,2 --kb-k 0,0,0,0 --out " + (dir / "bad.exr"));
  EXPECT_EQ(kb.rc, 1);
  EXPECT_NE(kb.err.find("need --lens kannala-brandt"), std::string::npos) << kb.err;
  EXPECT_EQ(dir.CountEntries(), before);
}

// The library names CaptureOptions' fields and their values; the CLI writes them as flags
// (tests/command_line_test.cc).
TEST(CaptureOptions, IsValidNamesTheFieldAndItsValue) {
  capture::CaptureOptions o;
  o.brackets = {"a.png", "b.png"};
  o.out = "f.exr";
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.width = 100;
  o.height = 100;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "CaptureOptions::width x height = 100x100 (expected a 2:1 lat-long between 16x8 and 16384x8192 pixels)");
  o.width = 200;
  o.north_longitude_deg = 400.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "CaptureOptions::north_longitude_deg = 400 (expected degrees in [-360, 360])");
}

}  // namespace
}  // namespace skycal
