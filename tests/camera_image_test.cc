// PNG in and out (core/png_io.h) and camera brackets from JPEG, PNG and TIFF
// (capture/src/camera_image.cc), against OpenCV's imgcodecs, which skycal used before and
// the tests still link as an independent reference: the same pixels, bit for bit, for every
// layout imread handled (grey, RGB, RGBA; 8 and 16 bits; JPEG through the same libjpeg).
#include <gtest/gtest.h>
#include <tiffio.h>
#include <zlib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "skycal/capture/hdr_merge.h"
#include "skycal/core/png_io.h"
#include "skycal/core/png_io_opencv.h"
#include "test_util.h"

namespace skycal {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

cv::Mat Noise(int rows, int cols, int type, unsigned seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  return m;
}

// The bracket as OpenCV's imread(ANYDEPTH | COLOR) gave it: BGR to RGB, codes as stored.
std::vector<uint16_t> ImreadRgb(const std::string& path, int* bits) {
  const cv::Mat m = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_COLOR);
  EXPECT_FALSE(m.empty()) << path;
  *bits = m.depth() == CV_16U ? 16 : 8;
  std::vector<uint16_t> rgb;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      for (int c = 2; c >= 0; --c)
        rgb.push_back(*bits == 16 ? m.at<cv::Vec3w>(y, x)[c] : m.at<cv::Vec3b>(y, x)[c]);
  return rgb;
}

// Every layout imread read, written by OpenCV: the same codes bit for bit.
TEST(CameraImage, JpegPngAndTiffDecodeAsImreadDid) {
  testing::ScratchDir dir("camera_image");
  struct Case {
    const char* name;
    int type;
  };
  const Case cases[] = {{"rgb8.png", CV_8UC3},   {"rgb16.png", CV_16UC3}, {"grey8.png", CV_8UC1},  {"grey16.png", CV_16UC1},
                        {"rgba8.png", CV_8UC4},  {"rgba16.png", CV_16UC4}, {"rgb8.tif", CV_8UC3},  {"rgb16.tif", CV_16UC3},
                        {"grey16.tif", CV_16UC1}, {"rgb.jpg", CV_8UC3},    {"grey.jpg", CV_8UC1}};
  unsigned seed = 1;
  for (const Case& c : cases) {
    const std::string path = dir / c.name;
    ASSERT_TRUE(cv::imwrite(path, Noise(37, 53, c.type, seed++), {cv::IMWRITE_JPEG_QUALITY, 90})) << c.name;
    int bits = 0;
    const std::vector<uint16_t> want = ImreadRgb(path, &bits);
    const capture::BracketImage got = capture::ReadBracketImage(path);
    EXPECT_EQ(got.width, 53) << c.name;
    EXPECT_EQ(got.height, 37) << c.name;
    EXPECT_EQ(got.bits, bits) << c.name;
    EXPECT_TRUE(got.rgb == want) << c.name;
  }
  // Control: the comparison sees a one-code difference.
  const std::string path = dir / "rgb8.png";
  int bits = 0;
  std::vector<uint16_t> want = ImreadRgb(path, &bits);
  want[want.size() / 2] ^= 1;
  EXPECT_FALSE(capture::ReadBracketImage(path).rgb == want);
}

// A 16-bit RGB TIFF written with libtiff, stored rows as given, with an Orientation tag.
void WriteTiff(const std::string& path, int w, int h, int orientation) {
  TIFF* t = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(t, nullptr);
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, w);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, h);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 3);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_ORIENTATION, orientation);
  std::vector<uint16_t> row(3 * w);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = static_cast<uint16_t>(1000 * y + x);
    TIFFWriteScanline(t, row.data(), y);
  }
  TIFFClose(t);
}

// EXIF/TIFF orientation, TIFF 6.0's meaning: 6 = the stored rows are the picture's columns,
// read right to left (turned 90 deg clockwise to view): displayed (x', y') = stored
// (y', H - 1 - x'); 8 the other way: stored (W - 1 - y', x'); 3 turned 180 deg. The stored
// code at (x, y) is 1000 y + x, so each displayed pixel says where it came from.
TEST(CameraImage, TheOrientationTagIsApplied) {
  testing::ScratchDir dir("camera_image_orientation");
  constexpr int W = 5, H = 3;
  auto code = [](int x, int y) { return 1000 * y + x; };
  for (int o : {1, 3, 6, 8}) {
    const std::string path = dir / ("o" + std::to_string(o) + ".tif");
    WriteTiff(path, W, H, o);
    const capture::BracketImage img = capture::ReadBracketImage(path);
    const bool swapped = o >= 5;
    ASSERT_EQ(img.width, swapped ? H : W) << o;
    ASSERT_EQ(img.height, swapped ? W : H) << o;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const int want = o == 1 ? code(x, y) : o == 3 ? code(W - 1 - x, H - 1 - y) : o == 6 ? code(y, H - 1 - x) : code(W - 1 - y, x);
        EXPECT_EQ(img.rgb[img.index(x, y)], want) << "orientation " << o << " at " << x << "," << y;
      }
  }
}

// Bad files name themselves and what failed; nothing is half-read.
TEST(CameraImage, BadFilesAreNamedWithWhatFailed) {
  testing::ScratchDir dir("camera_image_bad");
  const std::string jpg = dir / "cut.jpg", png = dir / "cut.png", bmp = dir / "photo.bmp";
  ASSERT_TRUE(cv::imwrite(jpg, Noise(64, 64, CV_8UC3, 9)));
  ASSERT_TRUE(cv::imwrite(png, Noise(64, 64, CV_8UC3, 9)));
  ASSERT_TRUE(cv::imwrite(bmp, Noise(8, 8, CV_8UC3, 9)));
  for (const std::string& p : {jpg, png}) {
    std::ifstream in(p, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 3));
  }
  EXPECT_NE(ErrorOf([&] { capture::ReadBracketImage(png); }).find("cut.png: cannot read image"), std::string::npos);
  const std::string bmp_error = ErrorOf([&] { capture::ReadBracketImage(bmp); });
  EXPECT_NE(bmp_error.find("photo.bmp: cannot read image (not a JPEG, PNG or TIFF"), std::string::npos) << bmp_error;
  // A cut JPEG: libjpeg fills the missing rows (a warning, as imread did) or fails; either
  // way no crash, and a failure names the file.
  const std::string jpg_error = ErrorOf([&] { capture::ReadBracketImage(jpg); });
  if (!jpg_error.empty()) {
    EXPECT_NE(jpg_error.find("cut.jpg: cannot read image"), std::string::npos) << jpg_error;
  }
}

// A damaged header that claims a huge image is refused before any pixel is allocated: a
// PNG's IHDR (its CRC recomputed, so libpng accepts the chunk) and a JPEG's SOF0 say
// 60000 x 60000. Control: the PNG unpatched decodes.
TEST(CameraImage, HeadersClaimingHugeImagesAreRefusedBeforeAllocating) {
  testing::ScratchDir dir("camera_image_huge");
  const cv::Mat m = Noise(16, 16, CV_8UC3, 5);
  std::vector<uint8_t> png = EncodePngFromMat(m, "small.png"), jpg;
  ASSERT_TRUE(cv::imencode(".jpg", m, jpg));
  ASSERT_EQ(DecodePng(std::string(png.begin(), png.end()), "small.png").width, 16);
  auto put32 = [](uint8_t* p, uint32_t v) { p[0] = v >> 24, p[1] = v >> 16, p[2] = v >> 8, p[3] = v; };
  put32(&png[16], 60000);  // IHDR width, height (after the 8-byte signature, length and type)
  put32(&png[20], 60000);
  put32(&png[29], static_cast<uint32_t>(crc32(0, &png[12], 17)));  // type + 13 data bytes
  for (size_t i = 2; i + 8 < jpg.size(); ++i) {
    if (jpg[i] == 0xFF && jpg[i + 1] == 0xC0) {  // SOF0: length (2), precision (1), height, width
      jpg[i + 5] = jpg[i + 7] = 0xEA, jpg[i + 6] = jpg[i + 8] = 0x60;
      break;
    }
  }
  const std::string png_path = dir / "huge.png", jpg_path = dir / "huge.jpg";
  std::ofstream(png_path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  std::ofstream(jpg_path, std::ios::binary).write(reinterpret_cast<const char*>(jpg.data()), static_cast<std::streamsize>(jpg.size()));
  for (const std::string& p : {png_path, jpg_path}) {
    const std::string e = ErrorOf([&] { capture::ReadBracketImage(p); });
    EXPECT_NE(e.find("cannot read image"), std::string::npos) << e;
    EXPECT_NE(e.find("60000 x 60000 pixels, more than skycal reads"), std::string::npos) << e;
  }
}

// EncodePng -> DecodePng is the identity for every layout, and OpenCV decodes the same codes
// from skycal's PNGs (channel order included: a Mat's BGR is the PNG's RGB).
TEST(PngIo, RoundTripsEveryLayoutAndOpenCvReadsTheSameCodes) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    const cv::Mat m = Noise(19, 23, type, static_cast<unsigned>(type));
    const std::vector<uint8_t> png = EncodePngFromMat(m, "test.png");
    const Raster r = DecodePng(std::string(png.begin(), png.end()), "test.png");
    EXPECT_TRUE(r.data == RasterFromMat(m, "test").data) << type;
    const cv::Mat back = cv::imdecode(png, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(back.type(), m.type()) << type;
    EXPECT_EQ(cv::norm(back, m, cv::NORM_INF), 0.0) << type;
  }
  Raster bad(4, 4, 3, 12);
  EXPECT_NE(ErrorOf([&] { EncodePng(bad, "bad.png"); }).find("bad.png: cannot encode"), std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodePng("GIF89a", "x.png"); }).find("x.png: not a PNG file"), std::string::npos);
}

}  // namespace
}  // namespace skycal
