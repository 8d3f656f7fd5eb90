// Camera RAW brackets (capture/raw_decode.h): DNGs written here with libtiff
// (tests/dng_writer.h) from a real HDR sky go through LibRaw and come back linear within the
// quantisation, with saturated pixels marked and left out of the merge, the exposure from the
// file, the camera matrix from ColorMatrix1, and bad files refused naming the file; 5 DNG
// brackets through `skycal capture` give back the sky.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <Eigen/Dense>

#include "dng_writer.h"
#include "run_binary.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/capture/raw_decode.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/capture/color_chart.h"
#include "skycal/testing/synthetic_brackets.h"
#include "skycal/testing/synthetic_chart.h"
#include "test_util.h"

namespace skycal {
namespace {

constexpr int kW = 512, kH = 256;

// The sky scaled so that its median is 0.18 of full scale: the sun and the bright horizon
// clip (v > 1), the rest spans ~9 stops.
ImageRGB ExposedSky(double* gain) {
  std::string source;
  ImageRGB sky = synthetic::LoadBracketScene(kW, kH, &source);
  std::vector<double> g;
  for (size_t p = 0; p < sky.pixels.size(); p += 3) g.push_back(sky.pixels[p + 1]);
  *gain = 0.18 / synthetic::Quantile(g, 0.5);
  for (float& v : sky.pixels) v = static_cast<float>(v * *gain);
  return sky;
}

std::string Write(const testing::ScratchDir& dir, const std::string& name, testing::DngSpec s, const ImageRGB& linear) {
  s.width = linear.width;
  s.height = linear.height;
  s.samples = testing::RawSamples(linear, s);
  const std::string path = dir / name;
  testing::WriteDng(path, s);
  return path;
}

// LinearRaw: every unsaturated value within the quantisation, every pixel with a sample at
// the white level marked and no other; the exposure and camera metadata come back.
TEST(RawDecode, LinearDngRoundTripsASkyWithinTheQuantisation) {
  testing::ScratchDir dir("raw-roundtrip");
  double gain = 0.0;
  const ImageRGB sky = ExposedSky(&gain);
  testing::DngSpec spec;
  spec.black = 512;  // a 14-bit camera's levels
  spec.white = 16383;
  spec.exposure_time_s = 1.0 / 250;
  spec.f_number = 5.6;
  spec.iso = 200;
  spec.focal_length_mm = 8.0;
  const std::string path = Write(dir, "sky.dng", spec, sky);

  const auto t0 = std::chrono::steady_clock::now();
  const capture::RawImage r = capture::ReadRawImage(path);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.image.width, kW);
  ASSERT_EQ(r.image.height, kH);
  EXPECT_EQ(r.image.bits, 16);
  EXPECT_TRUE(r.image.linear);
  EXPECT_EQ(r.black_level, 512.0);
  EXPECT_EQ(r.white_level, 16383.0);
  // Bound: the writer rounds to raw units (0.5 / (white - black) of full scale), LibRaw
  // scales to 16 bits truncating (< 1 / 65535).
  const double bound = 0.5 / (spec.white - spec.black) + 1.0 / 65535.0;
  double max_abs = 0.0;
  std::vector<double> rel;
  long long expected_saturated = 0, mismatched = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t p = static_cast<size_t>(y) * kW + x;
      bool sat = false;
      for (int c = 0; c < 3; ++c) sat |= testing::EncodeRaw(sky.at(x, y, c), spec.black, spec.white) >= spec.white;
      expected_saturated += sat;
      mismatched += sat != (r.image.saturated[p] != 0);
      if (sat) continue;
      for (int c = 0; c < 3; ++c) {
        const double truth = sky.at(x, y, c), got = r.image.rgb[3 * p + c] / 65535.0;
        max_abs = std::max(max_abs, std::fabs(got - truth));
        if (truth > 1e-3) rel.push_back(std::fabs(got - truth) / truth);
      }
    }
  std::sort(rel.begin(), rel.end());
  std::printf("[measured] RAW round trip %dx%d: max abs %.3g (bound %.3g), relative median %.3g, max %.3g "
              "(values > 1e-3); %lld saturated pixels; decode %.1f ms\n",
              kW, kH, max_abs, bound, rel[rel.size() / 2], rel.back(), expected_saturated, ms);
  EXPECT_LE(max_abs, bound * 1.001);
  EXPECT_GT(expected_saturated, 10);  // the sun clips
  EXPECT_EQ(mismatched, 0);
  EXPECT_EQ(r.saturated_pixels, expected_saturated);

  EXPECT_NEAR(r.metadata.exposure_time_s, 1.0 / 250, 1e-7);
  EXPECT_NEAR(r.metadata.f_number, 5.6, 1e-5);
  EXPECT_EQ(r.metadata.iso, 200.0);
  EXPECT_EQ(r.metadata.focal_length_mm, 8.0);
  EXPECT_EQ(r.metadata.make, "Skycal");
  EXPECT_EQ(r.metadata.model, "Test Camera");
  EXPECT_EQ(r.metadata.lens, "Skycal Test Lens 8mm");
  EXPECT_EQ(r.metadata.format, "dng");
  // ColorMatrix1 = XYZ -> Rec.709: the camera sees Rec.709, its matrix is the identity.
  ASSERT_TRUE(r.has_matrix);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(r.camera_to_rec709[i], i % 4 == 0 ? 1.0 : 0.0, 1e-3) << i;
  EXPECT_EQ(capture::ReadRawMetadata(path).iso, 200.0);
}

// A camera whose RGB mixes Rec.709 (camera = A rec709): the matrix is A^-1 up to the green
// normalisation (a D65 grey keeps its green value), and it takes the decoded camera RGB back
// to the sky's Rec.709 colours.
TEST(RawDecode, CameraMatrixComesFromColorMatrix1) {
  testing::ScratchDir dir("raw-matrix");
  Eigen::Matrix3d a;
  a << 0.70, 0.25, 0.05, 0.10, 0.85, 0.05, 0.02, 0.18, 0.80;
  Eigen::Matrix3d xyz_to_709;
  for (int i = 0; i < 9; ++i) xyz_to_709(i / 3, i % 3) = testing::kXyzToRec709[i];
  const Eigen::Matrix3d cm = a * xyz_to_709;  // XYZ -> camera
  testing::DngSpec spec;
  for (int i = 0; i < 9; ++i) spec.color_matrix1[i] = cm(i / 3, i % 3);
  ImageRGB sky(64, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const Eigen::Vector3d rec(0.05 + 0.3 * x / 64.0, 0.1 + 0.2 * y / 32.0, 0.4);
      const Eigen::Vector3d cam = a * rec;
      for (int c = 0; c < 3; ++c) sky.at(x, y, c) = static_cast<float>(cam[c]);
    }
  const capture::RawImage r = capture::ReadRawImage(Write(dir, "mixed.dng", spec, sky));
  ASSERT_TRUE(r.has_matrix);
  const double green_rowsum = a.row(1).sum();
  const Eigen::Matrix3d expected = green_rowsum * a.inverse();
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(r.camera_to_rec709[i], expected(i / 3, i % 3), 2e-3) << i;
  double worst = 0.0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const Eigen::Vector3d rec(0.05 + 0.3 * x / 64.0, 0.1 + 0.2 * y / 32.0, 0.4);
      Eigen::Vector3d cam, out = Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c) cam[c] = r.image.rgb[r.image.index(x, y) + c] / 65535.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i] += r.camera_to_rec709[3 * i + j] * cam[j];
      worst = std::max(worst, ((out / green_rowsum - rec).cwiseAbs().array() / rec.array()).maxCoeff());
    }
  std::printf("[measured] camera matrix: worst relative Rec.709 error %.3g\n", worst);
  EXPECT_LT(worst, 5e-3);
}

// An RGGB mosaic: demosaiced (AHD) within 2% on the smooth sky away from the edges, and a
// single saturated photosite marks the demosaic's 7x7 footprint.
TEST(RawDecode, BayerDngDemosaicsAndMarksTheFootprintOfASaturatedPhotosite) {
  testing::ScratchDir dir("raw-bayer");
  ImageRGB sky(64, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      sky.at(x, y, 0) = static_cast<float>(0.10 + 0.002 * x);
      sky.at(x, y, 1) = static_cast<float>(0.20 + 0.002 * y);
      sky.at(x, y, 2) = 0.45f;
    }
  sky.at(20, 20, 0) = 3.0f;  // a red photosite (even row, even column) past the white level
  testing::DngSpec spec;
  spec.cfa = true;
  spec.black = 256;
  spec.white = 4095;
  const capture::RawImage r = capture::ReadRawImage(Write(dir, "bayer.dng", spec, sky));
  EXPECT_EQ(r.metadata.format, "dng");
  ASSERT_EQ(r.image.width, 64);
  ASSERT_EQ(r.image.saturated.size(), 64u * 48u);
  EXPECT_EQ(r.saturated_pixels, 49);
  for (int y = 17; y <= 23; ++y)
    for (int x = 17; x <= 23; ++x) EXPECT_EQ(r.image.saturated[static_cast<size_t>(y) * 64 + x], 1) << x << "," << y;
  double worst = 0.0;
  for (int y = 4; y < 44; ++y)
    for (int x = 4; x < 60; ++x) {
      if (std::abs(x - 20) <= 4 && std::abs(y - 20) <= 4) continue;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::fabs(r.image.rgb[r.image.index(x, y) + c] / 65535.0 - sky.at(x, y, c)) / sky.at(x, y, c));
    }
  std::printf("[measured] Bayer AHD on a smooth sky: worst relative error %.3g\n", worst);
  EXPECT_LT(worst, 0.02);
}

// TIFF Orientation 6 (the stored rows are the picture's columns, read right to left): the
// decoded image is turned to stand upright, its mask with it.
TEST(RawDecode, OrientationIsApplied) {
  testing::ScratchDir dir("raw-orientation");
  constexpr int w = 40, h = 24;  // LibRaw takes nothing under 22 pixels a side
  ImageRGB img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(0.001 * (1 + x + w * y));
  img.at(0, 0, 1) = 2.0f;
  testing::DngSpec spec;
  spec.orientation = 6;
  const capture::RawImage r = capture::ReadRawImage(Write(dir, "turned.dng", spec, img));
  ASSERT_EQ(r.image.width, h);
  ASSERT_EQ(r.image.height, w);
  EXPECT_EQ(r.saturated_pixels, 1);
  // Orientation 6: displayed (x', y') = stored (y', H - 1 - x').
  for (int y = 0; y < w; ++y)
    for (int x = 0; x < h; ++x) {
      const int sx = y, sy = h - 1 - x;
      if (sx == 0 && sy == 0) {
        EXPECT_EQ(r.image.saturated[static_cast<size_t>(y) * h + x], 1);
        continue;
      }
      EXPECT_NEAR(r.image.rgb[r.image.index(x, y)] / 65535.0, img.at(sx, sy, 0), 1e-4) << x << "," << y;
    }
}

// Overwrites the first StripOffsets value of a little-endian TIFF's first directory.
void MoveStrip(const std::string& path, uint32_t offset) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  uint32_t ifd = 0;
  uint16_t n = 0;
  f.seekg(4);
  f.read(reinterpret_cast<char*>(&ifd), 4);
  f.seekg(ifd);
  f.read(reinterpret_cast<char*>(&n), 2);
  for (uint16_t i = 0; i < n; ++i) {
    uint16_t tag = 0;
    f.seekg(ifd + 2 + 12 * i);
    f.read(reinterpret_cast<char*>(&tag), 2);
    if (tag == 273) {  // StripOffsets, one LONG held in the entry
      f.seekp(ifd + 2 + 12 * i + 8);
      f.write(reinterpret_cast<const char*>(&offset), 4);
      return;
    }
  }
  FAIL() << path << ": no StripOffsets";
}

struct BadFiles {
  std::string truncated, short_data, corrupt, garbage, unsupported, empty, missing;
};

BadFiles MakeBadFiles(const testing::ScratchDir& dir) {
  ImageRGB img(64, 32);
  std::fill(img.pixels.begin(), img.pixels.end(), 0.3f);
  testing::DngSpec spec;
  const std::string good = Write(dir, "good.dng", spec, img);
  const auto size = std::filesystem::file_size(good);
  BadFiles b{dir / "truncated.dng", dir / "short_data.dng", dir / "corrupt.dng", dir / "garbage.nef",
             dir / "lzw.dng",       dir / "empty.cr2",      dir / "missing.arw"};
  std::filesystem::copy_file(good, b.truncated);
  std::filesystem::resize_file(b.truncated, size / 2);  // the directory (written last) is gone
  std::filesystem::copy_file(good, b.short_data);
  MoveStrip(b.short_data, static_cast<uint32_t>(size - 3000));  // the pixels run past the end
  std::filesystem::copy_file(good, b.corrupt);
  {
    std::fstream f(b.corrupt, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4);
    f.write("\xff\xff\xff\x7f", 4);  // the header's directory offset overwritten
  }
  {
    std::ofstream f(b.garbage, std::ios::binary);
    for (int i = 0; i < 5000; ++i) f.put(static_cast<char>(i * 7919 % 251));
  }
  spec.compression = COMPRESSION_LZW;  // a DNG compression LibRaw does not decode
  Write(dir, "lzw.dng", spec, img);
  std::ofstream(b.empty).close();
  return b;
}

TEST(RawDecode, BadFilesAreRefusedNamingTheFile) {
  testing::ScratchDir dir("raw-bad");
  const BadFiles b = MakeBadFiles(dir);
  for (const auto& [path, needle] : std::vector<std::pair<std::string, std::string>>{
           {b.truncated, "truncated or corrupt: its TIFF header points to a directory"},
           {b.short_data, "truncated camera RAW (the pixel data ends early"},
           {b.corrupt, "past the end of the file"},
           {b.garbage, "not a camera RAW file LibRaw decodes"},
           {b.unsupported, "unsupported format or compression"},
           {b.empty, "empty file"},
           {b.missing, "no such file"}}) {
    try {
      capture::ReadRawImage(path);
      ADD_FAILURE() << path << " accepted";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;  // the file first
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  }
}

// Two linear brackets; the long one marked saturated where its codes are below the hat's
// clip: the merge takes those pixels from the short bracket alone, reports the identity
// response, and refuses a recovered response for RAW input.
TEST(RawMerge, SaturatedPixelsGetZeroWeightAndTheResponseIsTheIdentity) {
  std::vector<capture::Bracket> b(2);
  for (int i = 0; i < 2; ++i) {
    b[i].path = "raw_" + std::to_string(i);
    b[i].exposure_time_s = i == 0 ? 0.01 : 0.04;
    b[i].image.width = 4;
    b[i].image.height = 2;
    b[i].image.bits = 16;
    b[i].image.linear = true;
    b[i].image.rgb.assign(4 * 2 * 3, static_cast<uint16_t>(i == 0 ? 10000 : 40000));
    b[i].image.saturated.assign(8, 0);
  }
  b[1].image.rgb[0] = b[1].image.rgb[1] = b[1].image.rgb[2] = 50000;  // pixel 0: wrong (bloom), marked
  b[1].image.saturated[0] = 1;
  const capture::MergeResult r = capture::MergeBrackets(b, {});
  const double from_short = 10000.0 / 65535.0 / 0.01;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.radiance.pixels[c], from_short, 1e-4 * from_short);
  for (int p = 1; p < 8; ++p) EXPECT_NEAR(r.radiance.pixels[3 * p], from_short, 1e-4 * from_short);  // both agree
  EXPECT_EQ(r.report["response"]["source"], "raw_linear");
  EXPECT_NE(r.report["response"]["method"].get<std::string>().find("camera RAW input is linear"), std::string::npos);
  EXPECT_NEAR(r.report["brackets"][1]["raw_saturated_fraction"].get<double>(), 1.0 / 8, 1e-12);
  capture::MergeOptions debevec;
  debevec.response = capture::ResponseModel::kDebevec;
  try {
    capture::MergeBrackets(b, debevec);
    ADD_FAILURE() << "a recovered response was accepted for RAW";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("response = debevec"), std::string::npos) << e.what();
  }
  b[1].image.linear = false;
  EXPECT_THROW(capture::MergeBrackets(b, {}), Error);  // RAW and non-RAW mixed
}

// The whole path: 5 DNG brackets 2 EV apart (t = 1/4000 s x 4^i, f/8, ISO 100 in their EXIF;
// no --exposure-times) of the HDR sky through `skycal capture --lens latlong` at the sky's own
// size. The frame is gain * sky (radiance = linear / (t ISO/100 / N^2), an identity camera
// matrix): compared over the frame's valid pixels. A truncated bracket among them is refused
// (exit 1, the file named) with nothing written.
TEST(RawCapture, FiveDngBracketsOfASkyThroughTheBinary) {
  testing::ScratchDir dir("raw-capture");
  std::string source;
  const ImageRGB sky = synthetic::LoadBracketScene(kW, kH, &source);
  std::vector<double> g;
  for (size_t p = 0; p < sky.pixels.size(); p += 3) g.push_back(sky.pixels[p + 1]);
  const double f_number = 8.0, k_mid = (1.0 / 4000 * 16) / (f_number * f_number);
  const double gain = 0.18 / (synthetic::Quantile(g, 0.5) * k_mid);  // the middle bracket's median at 0.18
  std::string args = "capture --json --lens latlong --size " + std::to_string(kW) + "x" + std::to_string(kH) + " --brackets";
  std::vector<std::string> paths;
  for (int i = 0; i < 5; ++i) {
    testing::DngSpec spec;
    spec.black = 512;
    spec.white = 16383;
    spec.exposure_time_s = 1.0 / 4000 * std::pow(4.0, i);
    spec.f_number = f_number;
    spec.iso = 100;
    const double k = spec.exposure_time_s / (f_number * f_number);
    ImageRGB linear = sky;
    for (float& v : linear.pixels) v = static_cast<float>(v * gain * k);
    paths.push_back(Write(dir, "bracket_" + std::to_string(i) + ".dng", spec, linear));
    args += " " + paths.back();
  }
  const std::string out = dir / "frame.exr";
  const auto r = testing::RunSkycal(SKYCAL_BINARY, args + " --out " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["merge"]["response"]["source"], "raw_linear");
  EXPECT_EQ(j["color_correction"]["source"], "camera RAW matrix (LibRaw rgb_cam x daylight pre_mul)");
  EXPECT_NEAR(j["merge"]["brackets"][0]["exposure_time_s"].get<double>(), 1.0 / 4000, 1e-9);
  EXPECT_EQ(j["merge"]["brackets"][4]["iso"], 100.0);

  const ExrRGB frame = ReadExrRGB(out);
  int w = 0, h = 0;
  const std::vector<float> valid = ReadExrChannel(out, "mask.valid", &w, &h);
  ASSERT_EQ(frame.image.width, kW);
  std::vector<double> rel;
  for (size_t p = 0; p < valid.size(); ++p) {
    if (valid[p] < 0.5f) continue;
    for (int c = 0; c < 3; ++c) {
      const double truth = gain * sky.pixels[3 * p + c];
      rel.push_back(std::fabs(frame.image.pixels[3 * p + c] - truth) / truth);
    }
  }
  ASSERT_GT(rel.size(), 3u * kW * kH * 9 / 10);
  const double median = synthetic::Quantile(rel, 0.5), p90 = synthetic::Quantile(rel, 0.9);
  std::printf("[measured] 5 DNG brackets -> skycal capture: %zu channel values, median rel %.3g, p90 %.3g\n",
              rel.size(), median, p90);
  // Tolerance: 14-bit quantisation (a value merged from its well-exposed brackets, the
  // brightest at >= 1/16 of full scale, is within ~1e-3 of it; the median far closer) and the
  // unwrap at the same size (lat-long to lat-long, node on node): 0.05% median, 0.2% p90.
  EXPECT_LT(median, 5e-4);
  EXPECT_LT(p90, 2e-3);

  // Options RAW makes contradictory: refused (exit 1), nothing written.
  const int before = dir.CountEntries();
  for (const auto& [extra, needle] : std::vector<std::pair<std::string, std::string>>{
           {"--response debevec", "are camera RAW, linear by construction"},
           {"--input-colorspace acescg", "acescg: the brackets are camera RAW"}}) {
    const auto bad = testing::RunSkycal(SKYCAL_BINARY, args + " " + extra + " --out " + (dir / "bad.exr"));
    EXPECT_EQ(bad.rc, 1) << extra;
    EXPECT_NE(bad.err.find(needle), std::string::npos) << bad.err;
  }
  EXPECT_EQ(dir.CountEntries(), before);
}

// Each bad RAW file as the third of five brackets: exit 1, the file named, nothing written.
TEST(RawCapture, BadBracketsAreRefusedByTheBinaryWithNothingWritten) {
  testing::ScratchDir dir("raw-capture-bad");
  const BadFiles b = MakeBadFiles(dir);
  ImageRGB img(64, 32);
  std::vector<std::string> good;
  for (int i = 0; i < 5; ++i) {
    std::fill(img.pixels.begin(), img.pixels.end(), static_cast<float>(0.01 * std::pow(4.0, i)));
    testing::DngSpec spec;
    spec.exposure_time_s = 0.001 * std::pow(4.0, i);
    good.push_back(Write(dir, "b" + std::to_string(i) + ".dng", spec, img));
  }
  const int before = dir.CountEntries();
  for (const std::string& bad : {b.truncated, b.short_data, b.corrupt, b.garbage, b.unsupported, b.empty, b.missing}) {
    std::string args = "capture --lens latlong --size 64x32 --out " + (dir / "frame.exr") + " --brackets";
    for (int i = 0; i < 5; ++i) args += " " + (i == 2 ? bad : good[i]);
    const auto r = testing::RunSkycal(SKYCAL_BINARY, args);
    EXPECT_EQ(r.rc, 1) << bad;
    EXPECT_NE(r.err.find(bad + ": "), std::string::npos) << r.err;
    EXPECT_EQ(dir.CountEntries(), before) << bad;
  }
  // Control: the good set is accepted.
  std::string args = "capture --lens latlong --size 64x32 --out " + (dir / "frame.exr") + " --brackets";
  for (const auto& g : good) args += " " + g;
  EXPECT_EQ(testing::RunSkycal(SKYCAL_BINARY, args).rc, 0);
  EXPECT_EQ(dir.CountEntries(), before + 1);
}

// A ColorChecker photographed in RAW (a camera whose RGB mixes Rec.709, camera = A rec709):
// read linear (the merge's curve is not applied to a RAW chart), the correction fitted from
// it takes the camera's RGB back to Rec.709; a patch past the white level is refused as clipped.
TEST(RawChart, AColorCheckerInRawIsReadLinearAndCorrects) {
  testing::ScratchDir dir("raw-chart");
  Eigen::Matrix3d a;
  a << 0.70, 0.25, 0.05, 0.10, 0.85, 0.05, 0.02, 0.18, 0.80;
  ImageRGB rec(200, 140);
  testing::ChartPlacement place;
  place.x0 = 10;
  place.y0 = 10;
  place.unit = 10;
  place.illuminance = 0.8;
  const std::array<double, 8> corners = testing::RenderChart(&rec, place);
  ImageRGB cam = rec;
  for (size_t p = 0; p < rec.pixels.size(); p += 3) {
    const Eigen::Vector3d v = a * Eigen::Vector3d(rec.pixels[p], rec.pixels[p + 1], rec.pixels[p + 2]);
    for (int c = 0; c < 3; ++c) cam.pixels[p + c] = static_cast<float>(v[c]);
  }
  testing::DngSpec spec;
  spec.black = 512;
  spec.white = 16383;
  const std::string path = Write(dir, "chart.dng", spec, cam);
  std::vector<float> srgb_curve(256 * 3);  // a bracket set's curve: must not touch the RAW chart
  for (int z = 0; z < 256; ++z)
    for (int c = 0; c < 3; ++c) srgb_curve[3 * z + c] = static_cast<float>(std::pow(z / 255.0, 2.2));
  capture::ChartOptions options;
  options.corners = corners;
  const capture::ColorCorrection cc = capture::CorrectionFromChartImage(path, srgb_curve, options, "raw");
  // The fitted matrix is A^-1 up to one scale (the correction keeps the white patch's level).
  const Eigen::Matrix3d inv = a.inverse();
  const double s = cc.matrix[4] / inv(1, 1);
  double worst = 0.0;
  for (int i = 0; i < 9; ++i) worst = std::max(worst, std::fabs(cc.matrix[i] - s * inv(i / 3, i % 3)));
  std::printf("[measured] RAW chart: correction within %.3g of A^-1 (scale %.4f)\n", worst, s);
  EXPECT_LT(worst, 0.01);
  // Overexposed: the white patch past the white level is clipped, and refused as such.
  for (float& v : cam.pixels) v *= 1.5f;
  const std::string hot = Write(dir, "hot.dng", spec, cam);
  try {
    capture::CorrectionFromChartImage(hot, {}, options, "raw");
    ADD_FAILURE() << "a clipped chart was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("clipped"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skycal
