// The import controller (controllers/import_controller.h): the in-memory frame is the one the
// file entry point writes, the convention is chosen from the envmap attribute when none is
// given, and bad options are refused naming the field (and, through the verb, the flag).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>

#include "import_verb.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/latlong_import.h"
#include "skycal/controllers/import_controller.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "test_util.h"

namespace skycal {
namespace {

constexpr double kPi = std::numbers::pi;

// A W x H Blender-convention sky of radiance 1 with a 1.5 deg sun of 5000 at Blender
// azimuth 60 deg, elevation 20 deg, and `nan_pixels` NaN pixels on row H / 4 (ringing).
ImageRGB BlenderSunSky(int w, int h, int nan_pixels) {
  ImageRGB img(w, h);
  const double az = 60.0 * kPi / 180.0, el = 20.0 * kPi / 180.0;
  const double sun[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double u = (i + 0.5) / w, v = 1.0 - (j + 0.5) / h;
      const double a = 2.0 * kPi * (0.5 - u), e = kPi * (v - 0.5);
      const double b[3] = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
      const double cosang = b[0] * sun[0] + b[1] * sun[1] + b[2] * sun[2];
      for (int c = 0; c < 3; ++c) img.at(i, j, c) = cosang > std::cos(1.5 * kPi / 180.0) ? 5000.0f : 1.0f;
    }
  for (int k = 0; k < nan_pixels; ++k)
    for (int c = 0; c < 3; ++c) img.at(10 + 2 * k, h / 4, c) = std::numeric_limits<float>::quiet_NaN();
  return img;
}

TEST(ImportController, InMemoryFrameIsTheFileWritten) {
  testing::ScratchDir dir("import-ctl-frame");
  const int w = 256, h = 128;
  WriteExrRGB(dir / "src.exr", BlenderSunSky(w, h, 3), {});
  controllers::ImportOptions o;
  o.in_path = dir / "src.exr";
  o.detect_sun = true;
  const controllers::ImportedPhoto p = controllers::ImportPhoto(o);  // out_path empty: nothing written
  EXPECT_EQ(dir.CountEntries(), 1);
  o.out_path = dir / "frame.exr";
  const controllers::ImportedFile f = controllers::ImportToFile(o);
  const capture::LatLongFrame back = capture::ReadLatLongFrame(o.out_path);

  ASSERT_EQ(back.radiance.width, w);
  ASSERT_EQ(back.radiance.height, h);
  ASSERT_EQ(p.frame.radiance.pixels.size(), back.radiance.pixels.size());
  long long differ = 0, non_finite = 0;
  for (size_t i = 0; i < back.radiance.pixels.size(); ++i) {
    differ += p.frame.radiance.pixels[i] != back.radiance.pixels[i];
    non_finite += !std::isfinite(p.frame.radiance.pixels[i]);
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(non_finite, 0);
  // 3 NaN source pixels, 3 channels each: each spreads to the nodes whose bilinear footprint
  // touches it (at least one), all zeroed.
  EXPECT_EQ(p.source_pixels.nan, 3);
  EXPECT_GE(p.zeroed, 9);
  EXPECT_EQ(p.zeroed, f.photo.zeroed);
  EXPECT_EQ(p.zeroed, 3 * p.frame_pixels.nan);

  ASSERT_TRUE(p.sun.direction.has_value());
  ASSERT_TRUE(back.sun_direction.has_value());
  EXPECT_EQ(p.sun.source, controllers::SunSource::kDisc);
  EXPECT_STREQ(controllers::ToString(p.sun.source), "disc");
  EXPECT_NEAR(latlong::ElevationDeg(*p.sun.direction), 20.0, 0.5);
  EXPECT_NEAR(latlong::AzimuthDeg(*p.sun.direction), 60.0, 0.5);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR((*back.sun_direction)[k], (*p.sun.direction)[k], 1e-7);  // stored as V3f
  EXPECT_TRUE(p.sun.refusal.empty());
  EXPECT_GT(p.sun.disc_contrast, 20.0);
  EXPECT_EQ(p.convention, capture::SourceConvention::kBlender);
  for (const char* key : {"skycalSource", "skycalSourceConvention", "skycalSunSource", "skycalUnits"})
    EXPECT_EQ(back.extra.strings.at(key), p.frame.extra.strings.at(key)) << key;
  EXPECT_EQ(back.extra.strings.at("skycalSunSource"), "detected");
  EXPECT_EQ(p.source_sha256.size(), 64u);
  EXPECT_EQ(p.warnings.size(), 1u);  // the NaN census
}

TEST(ImportController, ChoosesTheConventionFromTheEnvmapAttribute) {
  testing::ScratchDir dir("import-ctl-convention");
  const int w = 64, h = 32;
  ImageRGB img(w, h);
  for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<float>(0.5 + (i * 7919 % 1000) / 100.0);
  capture::LatLongFrame frame;  // written with envmap=latlong and a sunDirection
  frame.radiance = img;
  frame.sun_direction = std::array<double, 3>{0.0, 0.6, 0.8};
  capture::WriteLatLongFrame(dir / "project.exr", frame);
  WriteExrRGB(dir / "published.exr", img, {});  // no envmap attribute, as Poly Haven's

  EXPECT_EQ(capture::ChooseConvention(ReadExrRGB(dir / "project.exr").attributes), capture::SourceConvention::kExr);
  EXPECT_EQ(capture::ChooseConvention(ReadExrRGB(dir / "published.exr").attributes), capture::SourceConvention::kBlender);

  controllers::ImportOptions o;
  o.convention = std::nullopt;  // automatic
  o.in_path = dir / "project.exr";
  const controllers::ImportedPhoto a = controllers::ImportPhoto(o);
  EXPECT_EQ(a.convention, capture::SourceConvention::kExr);
  EXPECT_EQ(a.sun.source, controllers::SunSource::kAttribute);
  ASSERT_TRUE(a.sun.direction.has_value());
  EXPECT_NEAR((*a.sun.direction)[1], 0.6, 1e-6);
  EXPECT_TRUE(a.warnings.empty());
  // Same size, same convention: every node but the pole rows (their means) and the seam's
  // last column (the direction of column 0) is the source's.
  long long differ = 0;
  for (int y = 1; y < h - 1; ++y)
    for (int x = 0; x < w - 1; ++x)
      for (int c = 0; c < 3; ++c) differ += a.frame.radiance.at(x, y, c) != img.at(x, y, c);
  EXPECT_EQ(differ, 0);

  o.in_path = dir / "published.exr";
  const controllers::ImportedPhoto b = controllers::ImportPhoto(o);
  EXPECT_EQ(b.convention, capture::SourceConvention::kBlender);
  EXPECT_EQ(b.sun.source, controllers::SunSource::kNone);
  EXPECT_FALSE(b.sun.direction.has_value());

  // Told blender, a file that claims envmap=latlong gets a warning naming the field.
  o.in_path = dir / "project.exr";
  o.convention = capture::SourceConvention::kBlender;
  const controllers::ImportedPhoto c = controllers::ImportPhoto(o);
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("pass ImportOptions::convention = exr"), std::string::npos) << c.warnings[0];
  EXPECT_EQ(c.sun.source, controllers::SunSource::kNone);  // the attribute is trusted only in the exr convention
}

TEST(ImportController, IsValidNamesTheFieldAndTheVerbTheFlag) {
  controllers::ImportOptions o;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ImportOptions::in_path is not set (expected the source picture: OpenEXR or Radiance .hdr)");
  o.in_path = "sky.exr";
  EXPECT_TRUE(o.IsValid(&why));  // an empty out_path: ImportPhoto writes nothing
  o.out_path = "frame.png";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ImportOptions::out_path = frame.png (expected a path ending in .exr)");
  o.out_path = "frame.exr";
  o.min_sun_contrast = 0.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ImportOptions::min_sun_contrast = 0.5 (expected a ratio >= 1)");
  o.min_sun_contrast = 20.0;
  o.sun_dir = std::array<double, 3>{0.0, 0.0, 0.0};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ImportOptions::sun_dir = 0,0,0 (expected a finite, non-zero vector)");
  o.sun_dir = std::array<double, 3>{0.0, 1.0, 0.0};
  o.detect_sun = true;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ImportOptions::sun_dir and ImportOptions::detect_sun are both set (expected one, not both)");

  // The verb says the flags the user typed.
  o.sun_dir.reset();
  o.min_sun_contrast = 0.5;
  try {
    cli::RunImportImpl(o);
    ADD_FAILURE() << "an invalid --min-sun-contrast was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "--min-sun-contrast 0.5 (expected a ratio >= 1)");
  }
}

TEST(ImportController, NoSunFoundIsAReasonInMemoryAndARefusalOnFile) {
  testing::ScratchDir dir("import-ctl-nosun");
  ImageRGB img(64, 32);
  for (float& v : img.pixels) v = 3.0f;  // overcast: no disc, no luminance pattern
  WriteExrRGB(dir / "src.exr", img, {});
  controllers::ImportOptions o;
  o.in_path = dir / "src.exr";
  o.detect_sun = true;
  const controllers::ImportedPhoto p = controllers::ImportPhoto(o);
  EXPECT_FALSE(p.sun.direction.has_value());
  EXPECT_EQ(p.sun.source, controllers::SunSource::kNone);
  EXPECT_EQ(p.sun.refusal.rfind("no sun disc (", 0), 0u) << p.sun.refusal;
  EXPECT_EQ(p.frame.extra.strings.at("skycalSunSource"), "none");

  o.out_path = dir / "frame.exr";
  try {
    controllers::ImportToFile(o);
    ADD_FAILURE() << "a detect_sun without a sun was written";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), o.in_path + ": ImportOptions::detect_sun: " + p.sun.refusal + "; nothing written");
  }
  EXPECT_EQ(dir.CountEntries(), 1);  // only the source
}

// A Radiance picture imports as its OpenEXR twin: tests/data/radiance holds one float image
// written by OpenCV as .hdr and as .exr (neither carries envmap, so both are read in Blender's
// convention). The frames agree within RGBE's precision (half a mantissa step of the pixel's
// largest channel); the frame says where it came from; a truncated picture is refused by name
// and leaves nothing.
TEST(ImportController, ARadiancePictureImportsAsItsExrTwin) {
  const std::string data = std::string(SKYCAL_SOURCE_DIR) + "/tests/data/radiance/";
  controllers::ImportOptions o;
  o.in_path = data + "opencv_64x32.hdr";
  const controllers::ImportedPhoto hdr = controllers::ImportPhoto(o);
  o.in_path = data + "opencv_64x32.exr";
  const controllers::ImportedPhoto exr = controllers::ImportPhoto(o);
  EXPECT_EQ(hdr.convention, capture::SourceConvention::kBlender);
  ASSERT_EQ(hdr.frame.radiance.pixels.size(), exr.frame.radiance.pixels.size());
  // The conversion to the project's layout interpolates between neighbours: the bound is the
  // largest channel over the pixel's 3 x 3 neighbourhood.
  const ImageRGB& e = exr.frame.radiance;
  long long outside = 0;
  for (int y = 0; y < e.height; ++y)
    for (int x = 0; x < e.width; ++x) {
      float m = 0.0f;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          for (int c = 0; c < 3; ++c)
            m = std::max(m, e.at((x + dx + e.width) % e.width, std::clamp(y + dy, 0, e.height - 1), c));
      for (int c = 0; c < 3; ++c) outside += !(std::abs(hdr.frame.radiance.at(x, y, c) - e.at(x, y, c)) <= m / 256.0f + 1e-30f);
    }
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(hdr.frame.extra.strings.at("skycalSourceFormat"), "Radiance RGBE (-Y 32 +X 64, EXPOSURE 1 divided out)");
  EXPECT_EQ(exr.frame.extra.strings.at("skycalSourceFormat"), "OpenEXR");
  testing::ScratchDir dir("import-ctl-radiance");
  std::filesystem::copy_file(data + "opencv_64x32.hdr", dir / "cut.hdr");
  std::filesystem::resize_file(dir / "cut.hdr", 1000);
  o.in_path = dir / "cut.hdr";
  o.out_path = dir / "frame.exr";
  try {
    controllers::ImportToFile(o);
    ADD_FAILURE() << "a truncated picture was imported";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir / "cut.hdr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dir.CountEntries(), 1);  // only the source
  // A JPEG, PNG or TIFF is not an HDR picture: said so, and what to do; a text file is left
  // to the OpenEXR reader's message.
  struct Case { const char* name; std::string bytes; const char* said; };
  for (const Case& c : {Case{"pano.jpg", std::string("\xff\xd8\xff\xe0JFIF", 9), "a JPEG image, not an HDR picture"},
                        Case{"pano.png", std::string("\x89PNG\r\n\x1a\n", 8), "a PNG image, not an HDR picture"},
                        Case{"pano.tif", std::string("II*\0\x08\0\0\0", 8), "a TIFF image, not an HDR picture"},
                        Case{"pano.exr", std::string("not an image"), "OpenEXR"}}) {
    testing::WriteText(dir / c.name, c.bytes);
    o.in_path = dir / c.name;
    try {
      controllers::ImportPhoto(o);
      ADD_FAILURE() << c.name << " was imported";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(dir / c.name + ": "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.said), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace skycal
