// A photo's time and place (capture/time_place.h): EXIF written and read back through exiv2
// (the GPS UTC stamps first, else DateTimeOriginal with its offset; a local time without an
// offset is not a time), and OpenEXR's standard attributes both ways, malformed ones refused
// by name.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "skycal/capture/capture_pipeline.h"
#include "skycal/capture/exif_exposure.h"
#include "skycal/capture/time_place.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "test_util.h"

namespace skycal {
namespace {

std::string Jpeg(const testing::ScratchDir& dir, const std::string& name) {
  const std::string path = dir / name;
  cv::imwrite(path, cv::Mat(8, 8, CV_8UC3, cv::Scalar(90, 120, 200)));
  return path;
}

TEST(TimePlace, ExifRoundTrip) {
  testing::ScratchDir dir("time-place-exif");
  const std::string path = Jpeg(dir, "a.jpg");
  const capture::TimePlace none = capture::ReadExifTimePlace(path);
  EXPECT_FALSE(none.complete());
  EXPECT_EQ(none.why_no_time, "no EXIF block");
  capture::TimePlace t;
  t.time_iso8601 = "2026-06-21T06:30:15-04:00";
  t.latitude_deg = -33.8568;  // south and west: the refs carry the signs
  t.longitude_deg = -70.6483;
  t.altitude_m = 570.0;
  capture::WriteExifTimePlace(path, t);
  const capture::TimePlace back = capture::ReadExifTimePlace(path);
  ASSERT_TRUE(back.complete()) << back.why_no_time;
  EXPECT_EQ(back.time_iso8601, t.time_iso8601);
  EXPECT_EQ(back.source, "EXIF DateTimeOriginal + OffsetTimeOriginal");
  // Degrees, minutes and 1/1000 s of arc: 1/3.6e6 deg.
  EXPECT_NEAR(*back.latitude_deg, *t.latitude_deg, 3e-7);
  EXPECT_NEAR(*back.longitude_deg, *t.longitude_deg, 3e-7);
  EXPECT_NEAR(*back.altitude_m, 570.0, 1e-9);
}

TEST(TimePlace, ExifLocalTimeWithoutOffsetIsNotATime) {
  testing::ScratchDir dir("time-place-local");
  const std::string path = Jpeg(dir, "b.jpg");
  capture::TimePlace t;
  t.latitude_deg = 45.0;
  t.longitude_deg = 7.0;
  t.time_iso8601 = "2026-06-21T06:30:00";  // a camera without Exif 2.31's offset tags
  capture::WriteExifTimePlace(path, t);
  const capture::TimePlace local = capture::ReadExifTimePlace(path);
  EXPECT_FALSE(local.complete());
  EXPECT_TRUE(local.time_iso8601.empty());
  EXPECT_EQ(local.why_no_time, "DateTimeOriginal without OffsetTimeOriginal: the local time of an unknown zone");
  EXPECT_NEAR(*local.latitude_deg, 45.0, 1e-9);
  const std::string bare = Jpeg(dir, "c.jpg");
  capture::TimePlace place_only;
  place_only.latitude_deg = 45.0;
  place_only.longitude_deg = 7.0;
  capture::WriteExifTimePlace(bare, place_only);
  const capture::TimePlace p = capture::ReadExifTimePlace(bare);
  EXPECT_FALSE(p.complete());
  EXPECT_EQ(p.why_no_time, "no DateTimeOriginal or GPS time stamp in the EXIF");
  EXPECT_THROW(capture::ReadExifTimePlace(dir / "missing.jpg"), Error);
}

TEST(TimePlace, ExrStandardAttributesBothWays) {
  capture::TimePlace t;
  t.time_iso8601 = "2026-12-01T23:05:00+05:30";
  t.latitude_deg = 12.97;
  t.longitude_deg = 77.59;
  ExrAttributes a;
  capture::AddTimePlaceAttributes(t, &a);
  EXPECT_EQ(a.strings.at("capDate"), "2026:12:01 23:05:00");
  EXPECT_FLOAT_EQ(a.floats.at("utcOffset"), -19800.0f);  // UTC = local + utcOffset
  const capture::TimePlace back = capture::TimePlaceFromExrAttributes(a, "x.exr");
  ASSERT_TRUE(back.complete()) << back.why_no_time;
  EXPECT_EQ(back.time_iso8601, t.time_iso8601);
  EXPECT_NEAR(*back.latitude_deg, 12.97, 1e-5);  // stored as float
  a.floats.erase("utcOffset");
  EXPECT_EQ(capture::TimePlaceFromExrAttributes(a, "x.exr").why_no_time,
            "capDate without utcOffset: the local time of an unknown zone");
  a.strings["capDate"] = "2026-12-01 23:05";
  try {
    capture::TimePlaceFromExrAttributes(a, "x.exr");
    ADD_FAILURE() << "a malformed capDate was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.exr: attribute 'capDate' = '2026-12-01 23:05'"), std::string::npos) << e.what();
  }
  a.strings.erase("capDate");
  a.floats["latitude"] = 123.0f;
  EXPECT_THROW(capture::TimePlaceFromExrAttributes(a, "x.exr"), Error);
}

// `capture` of brackets whose EXIF says when and where: the frame carries it as OpenEXR's
// standard attributes (what `calibrate` reads), and its summary says where it came from.
TEST(TimePlace, CaptureCarriesTheBracketsExifIntoTheFrame) {
  testing::ScratchDir dir("time-place-capture");
  capture::CaptureOptions o;
  for (int i = 0; i < 2; ++i) {
    cv::Mat img(32, 64, CV_8UC3);
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) img.at<cv::Vec3b>(y, x) = cv::Vec3b(60 + x + 60 * i, 80 + y + 60 * i, 100 + 60 * i);
    o.brackets.push_back(dir / ("b" + std::to_string(i) + ".jpg"));
    ASSERT_TRUE(cv::imwrite(o.brackets.back(), img));
    capture::ExifExposure e;
    e.exposure_time_s = i == 0 ? 1.0 / 250 : 1.0 / 60;
    capture::WriteExifExposure(o.brackets.back(), e);
  }
  capture::TimePlace t;
  t.time_iso8601 = "2026-06-21T06:30:00+02:00";
  t.latitude_deg = 47.5;
  t.longitude_deg = 8.25;
  capture::WriteExifTimePlace(o.brackets.front(), t);
  o.merge.response = capture::ResponseModel::kSrgb;
  o.lens.model = capture::LensModel::kLatLong;
  o.width = 64;
  o.height = 32;
  o.out = dir / "frame.exr";
  o.verbose = false;
  const nlohmann::json summary = capture::RunCapturePipeline(o);
  EXPECT_EQ(summary["time_place"]["source"], "EXIF DateTimeOriginal + OffsetTimeOriginal") << summary["time_place"];
  const ExrRGB frame = ReadExrRGB(o.out);
  const capture::TimePlace back = capture::TimePlaceFromExrAttributes(frame.attributes, o.out);
  ASSERT_TRUE(back.complete()) << back.why_no_time;
  EXPECT_EQ(back.time_iso8601, t.time_iso8601);
  EXPECT_NEAR(*back.latitude_deg, 47.5, 1e-5);
  EXPECT_NEAR(*back.longitude_deg, 8.25, 1e-5);
}

}  // namespace
}  // namespace skycal
