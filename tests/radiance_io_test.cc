// Radiance pictures (core/radiance_io.h): the decoding rule on known bytes, round trips
// through an RGBE encoder written here from the format (both scanline encodings, both row
// orders), parity with OpenCV's independent encoder (tests/data/radiance: one float image
// written by OpenCV 4.6 as .hdr and as .exr), and every refusal naming the file and field.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/radiance_io.h"

namespace skycal {
namespace {

using Bytes = std::vector<unsigned char>;

void Append(Bytes* b, const std::string& s) { b->insert(b->end(), s.begin(), s.end()); }

// A truncating encoder, as Radiance's setcolr: the largest channel's mantissa in [128, 256).
std::array<unsigned char, 4> Rgbe(float r, float g, float b) {
  const float m = std::max({r, g, b});
  if (!(m > 1e-32f)) return {0, 0, 0, 0};
  int e = 0;
  const double scale = std::frexp(m, &e) * 256.0 / m;
  return {static_cast<unsigned char>(r * scale), static_cast<unsigned char>(g * scale),
          static_cast<unsigned char>(b * scale), static_cast<unsigned char>(e + 128)};
}

// The adaptive run-length scheme: runs of 4 or more equal bytes become runs, the rest dumps.
void AppendRunLength(Bytes* out, const std::vector<std::array<unsigned char, 4>>& row) {
  const int w = static_cast<int>(row.size());
  Append(out, std::string{2, 2, static_cast<char>(w >> 8), static_cast<char>(w & 0xff)});
  for (int k = 0; k < 4; ++k) {
    int i = 0;
    while (i < w) {
      int run = 1;
      while (i + run < w && run < 127 && row[i + run][k] == row[i][k]) ++run;
      if (run >= 4) {
        out->push_back(static_cast<unsigned char>(128 + run));
        out->push_back(row[i][k]);
        i += run;
        continue;
      }
      int dump = 0;
      while (i + dump < w && dump < 128) {
        int r = 1;
        while (i + dump + r < w && r < 4 && row[i + dump + r][k] == row[i + dump][k]) ++r;
        if (r >= 4) break;
        ++dump;
      }
      out->push_back(static_cast<unsigned char>(dump));
      for (int z = 0; z < dump; ++z) out->push_back(row[i + z][k]);
      i += dump;
    }
  }
}

// The picture of `img`: rows run-length encoded where the width allows and `flat_rows` does
// not name them; "+Y" writes the bottom row first.
Bytes Encode(const ImageRGB& img, const std::string& header, bool bottom_up = false, const std::vector<int>& flat_rows = {}) {
  Bytes out;
  Append(&out, "#?RADIANCE\n" + header + "\n" + (bottom_up ? "+Y " : "-Y ") + std::to_string(img.height) + " +X " +
                   std::to_string(img.width) + "\n");
  for (int j = 0; j < img.height; ++j) {
    const int y = bottom_up ? img.height - 1 - j : j;
    std::vector<std::array<unsigned char, 4>> row;
    for (int x = 0; x < img.width; ++x) row.push_back(Rgbe(img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)));
    const bool flat = img.width < 8 || std::find(flat_rows.begin(), flat_rows.end(), y) != flat_rows.end();
    if (!flat) {
      AppendRunLength(&out, row);
      continue;
    }
    for (const auto& p : row) out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

ImageRGB TestImage(int w, int h) {
  ImageRGB img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool patch = x >= w / 4 && x < w / 2 && y >= h / 2;  // equal pixels: runs
      img.at(x, y, 0) = patch ? 2.0f : 1e-3f * std::pow(10.0f, 7.0f * x / w);
      img.at(x, y, 1) = patch ? 3.0f : 0.5f + y;
      img.at(x, y, 2) = patch ? 4.0f : (y == 1 ? 0.0f : 40.0f / (1 + x + y));
    }
  for (int c = 0; c < 3; ++c) img.at(0, 0, c) = 0.0f;  // a black pixel (exponent 0)
  return img;
}

// Each channel within half a mantissa step of the pixel's largest channel (0.39%).
void ExpectWithinRgbePrecision(const ImageRGB& got, const ImageRGB& want, const std::string& what) {
  ASSERT_EQ(got.width, want.width) << what;
  ASSERT_EQ(got.height, want.height) << what;
  int bad = 0;
  for (int y = 0; y < want.height; ++y)
    for (int x = 0; x < want.width; ++x) {
      const float m = std::max({want.at(x, y, 0), want.at(x, y, 1), want.at(x, y, 2)});
      for (int c = 0; c < 3; ++c)
        if (!(std::abs(got.at(x, y, c) - want.at(x, y, c)) <= m / 256.0f + 1e-30f)) ++bad;
    }
  EXPECT_EQ(bad, 0) << what;
}

TEST(RadiancePicture, KnownBytesDecodeToTheCentreOfTheirBin) {
  Bytes b;
  Append(&b, "#?RADIANCE\nEXPOSURE=2\nEXPOSURE=0.5\nEXPOSURE=4\nCOLORCORR=1 2 4\n\n-Y 1 +X 2\n");
  b.insert(b.end(), {128, 64, 0, 129, 0, 0, 0, 0});  // flat (width 2 < 8)
  const RadiancePicture p = DecodeRadiancePicture(b, "known.hdr");
  EXPECT_DOUBLE_EQ(p.header.exposure, 4.0);
  // (mantissa + 0.5) x 2^(129 - 136), then / exposure 4 and / COLORCORR.
  EXPECT_FLOAT_EQ(p.image.at(0, 0, 0), 128.5f / 128.0f / 4.0f);
  EXPECT_FLOAT_EQ(p.image.at(0, 0, 1), 64.5f / 128.0f / 4.0f / 2.0f);
  EXPECT_FLOAT_EQ(p.image.at(0, 0, 2), 0.5f / 128.0f / 4.0f / 4.0f);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(p.image.at(1, 0, c), 0.0f);  // exponent 0: black
  EXPECT_TRUE(p.warnings.empty());
  // PRIMARIES: Rec.709's are read without a word; Radiance's own defaults are reported.
  const auto with_primaries = [&](const std::string& line) {
    Bytes q;
    Append(&q, "#?RADIANCE\nPRIMARIES=" + line + "\n\n-Y 1 +X 2\n");
    q.insert(q.end(), {128, 64, 0, 129, 0, 0, 0, 0});
    return DecodeRadiancePicture(q, "primaries.hdr").warnings;
  };
  EXPECT_TRUE(with_primaries("0.640 0.330 0.300 0.600 0.150 0.060 0.3127 0.3290").empty());
  const auto warned = with_primaries("0.640 0.330 0.290 0.600 0.150 0.060 0.333 0.333");
  ASSERT_EQ(warned.size(), 1u);
  EXPECT_NE(warned[0].find("primaries.hdr: PRIMARIES=0.640 0.330 0.290"), std::string::npos) << warned[0];
}

TEST(RadiancePicture, RoundTripsBothEncodingsAndBothRowOrders) {
  const ImageRGB img = TestImage(64, 16);
  ExpectWithinRgbePrecision(DecodeRadiancePicture(Encode(img, "FORMAT=32-bit_rle_rgbe\n"), "rle").image, img, "rle");
  ExpectWithinRgbePrecision(DecodeRadiancePicture(Encode(img, "", false, {0, 3, 15}), "mixed").image, img, "mixed");
  ExpectWithinRgbePrecision(DecodeRadiancePicture(Encode(img, "", true), "+Y").image, img, "+Y");
  const ImageRGB narrow = TestImage(6, 3);  // below 8 pixels: always flat
  ExpectWithinRgbePrecision(DecodeRadiancePicture(Encode(narrow, ""), "flat").image, narrow, "flat");
  // The wrong control: the encoder's bytes read as the opposite row order are not the image.
  const ImageRGB flipped = DecodeRadiancePicture(Encode(img, "", true), "x").image;
  const ImageRGB upside = DecodeRadiancePicture(Encode(img, "", false), "x").image;
  EXPECT_NE(flipped.at(5, 1, 2), upside.at(5, img.height - 2, 2));
}

TEST(RadiancePicture, MatchesOpenCvsEncoderOfTheSameImage) {
  const std::string dir = std::string(SKYCAL_SOURCE_DIR) + "/tests/data/radiance/";
  ASSERT_TRUE(IsRadiancePicture(dir + "opencv_64x32.hdr"));
  EXPECT_FALSE(IsRadiancePicture(dir + "opencv_64x32.exr"));
  EXPECT_FALSE(IsRadiancePicture(dir + "absent.hdr"));
  const RadiancePicture p = ReadRadiancePicture(dir + "opencv_64x32.hdr");
  EXPECT_EQ(p.header.resolution, "-Y 32 +X 64");
  ExpectWithinRgbePrecision(p.image, ReadExrRGB(dir + "opencv_64x32.exr").image, "OpenCV's .hdr against its .exr");
}

// What a bad picture is refused with: the file's name and the field.
void ExpectRefused(const Bytes& b, const std::string& needle) {
  try {
    DecodeRadiancePicture(b, "bad.hdr");
    ADD_FAILURE() << "accepted; expected an error containing '" << needle << "'";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad.hdr"), std::string::npos) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

Bytes WithHeader(const std::string& header, const std::string& resolution, const Bytes& body = {}) {
  Bytes b;
  Append(&b, "#?RADIANCE\n" + header + "\n" + resolution + "\n");
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

TEST(RadiancePicture, BadPicturesAreRefusedNamingTheFileAndField) {
  const Bytes pixel4 = {128, 128, 128, 129, 128, 128, 128, 129, 128, 128, 128, 129, 128, 128, 128, 129};
  ExpectRefused({'P', '3', '\n'}, "not a Radiance picture");
  ExpectRefused(WithHeader("FORMAT=32-bit_rle_xyze\n", "-Y 1 +X 4", pixel4), "FORMAT=32-bit_rle_xyze");
  ExpectRefused(WithHeader("EXPOSURE=0\n", "-Y 1 +X 4", pixel4), "EXPOSURE=0");
  ExpectRefused(WithHeader("COLORCORR=1 1\n", "-Y 1 +X 4", pixel4), "COLORCORR=1 1");
  ExpectRefused(WithHeader("EXPOSURE=1e-200\nEXPOSURE=1e-200\n", "-Y 1 +X 4", pixel4), "product of the EXPOSURE");
  ExpectRefused(WithHeader("EXPOSURE=1e-300\n", "-Y 1 +X 4", {255, 1, 1, 255, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}),
                "scanline 0: pixel 0 is");
  ExpectRefused(WithHeader("", "+X 4 -Y 1", pixel4), "resolution string '+X 4 -Y 1'");
  ExpectRefused(WithHeader("", "-Y 1 -X 4", pixel4), "rotated or mirrored");
  ExpectRefused(WithHeader("", "-Y 0 +X 4", pixel4), "bad.hdr");
  Bytes no_blank;
  Append(&no_blank, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n");
  ExpectRefused(no_blank, "no blank line");
  // A header claiming the largest picture over 16 bytes: refused before anything is allocated.
  const auto t0 = std::chrono::steady_clock::now();
  ExpectRefused(WithHeader("", "-Y 16384 +X 32768", pixel4), "bytes of scanlines, the file has 16");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  ExpectRefused(WithHeader("", "-Y 16385 +X 32768", pixel4), "larger than");
  // Run-length scanlines: a wrong length, a run of 0 at the end of the data (stb_image 2.27
  // loops forever there, CVE-2021-42715), a run past the scanline's end, a cut dump.
  const ImageRGB img = TestImage(16, 2);
  Bytes good = Encode(img, "");
  ASSERT_NO_THROW(DecodeRadiancePicture(good, "good.hdr"));
  const size_t data = WithHeader("", "-Y 2 +X 16").size();  // the first scanline's marker
  Bytes wrong_length = good;
  wrong_length[data + 3] = 15;
  ExpectRefused(wrong_length, "its run-length marker gives 15 pixels (expected 16)");
  Bytes zero_run = WithHeader("", "-Y 1 +X 16", {2, 2, 0, 16});
  zero_run.resize(zero_run.size() + 60, 0);  // enough bytes for the size check, every count 0
  ExpectRefused(zero_run, "a run of 0 at pixel 0 of 16");
  Bytes overrun = WithHeader("", "-Y 1 +X 16", {2, 2, 0, 16, 128 + 17, 7});
  overrun.resize(overrun.size() + 60, 1);
  ExpectRefused(overrun, "a run of 17 at pixel 0 of 16 (expected 1..16)");
  Bytes cut = WithHeader("", "-Y 1 +X 16", {2, 2, 0, 16, 16});
  cut.resize(cut.size() + 35, 1);  // the size check passes; the 16-byte dumps run out
  ExpectRefused(cut, "scanline 0 is truncated");
}

TEST(RadiancePicture, AnUnreadableFileIsNamed) {
  // A FIFO is not opened (nothing writes to it: a read would wait forever), by the magic
  // tests nor by the reader.
  const std::string fifo = (std::filesystem::temp_directory_path() / "skycal_radiance_fifo.hdr").string();
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_FALSE(IsRadiancePicture(fifo));
  EXPECT_FALSE(IsOpenExrFile(fifo));
  try {
    ReadRadiancePicture(fifo);
    ADD_FAILURE() << "a FIFO was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fifo + ": is not a regular file"), std::string::npos) << e.what();
  }
  std::filesystem::remove(fifo);
  const std::string path = (std::filesystem::temp_directory_path() / "skycal_radiance_missing.hdr").string();
  std::filesystem::remove(path);
  try {
    ReadRadiancePicture(path);
    ADD_FAILURE() << "a missing file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot open"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skycal
