// Writes a display preview as an 8-bit PNG, atomically.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/output_kind.h"

namespace skycal::color {
namespace {

// PNG bytes for an interleaved 8-bit RGB buffer. OpenCV expects BGR, so swap while
// copying; imencode (rather than imwrite) lets us write the bytes to a temporary name
// whose extension OpenCV would not recognise.
std::vector<uint8_t> EncodePng(const std::vector<uint8_t>& rgb, int width, int height) {
  cv::Mat bgr(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* src = rgb.data() + static_cast<size_t>(y) * width * 3;
    uint8_t* dst = bgr.ptr<uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      dst[3 * x + 0] = src[3 * x + 2];
      dst[3 * x + 1] = src[3 * x + 1];
      dst[3 * x + 2] = src[3 * x + 0];
    }
  }
  std::vector<uint8_t> png;
  // Compression level 6: zlib's default balance; previews are written once, read often.
  if (!cv::imencode(".png", bgr, png, {cv::IMWRITE_PNG_COMPRESSION, 6})) {
    throw Error("PNG encoding failed");
  }
  return png;
}

}  // namespace

PreviewReport WritePreviewPng(const ImageRGB& linear, const std::string& png_path, const PreviewOptions& options) {
  // Check the destination first (cheap, and AtomicOutput's errors name the path).
  RefuseMismatchedExtension(png_path, ".png", "a PNG preview");
  AtomicOutput out(png_path);
  PreviewReport report;
  std::vector<uint8_t> png;
  try {
    const std::vector<uint8_t> rgb = ToDisplay8(linear, options, &report);
    png = EncodePng(rgb, linear.width, linear.height);
  } catch (const Error& e) {
    throw Error(png_path + ": " + e.what());
  } catch (const cv::Exception& e) {
    throw Error(png_path + ": PNG encoding failed (" + e.what() + ")");
  }
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    f.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    f.flush();
    if (!f) throw Error(png_path + ": write failed (" + std::strerror(errno) + ")");
  }  // closed before the rename; ~AtomicOutput removes the temporary if anything threw
  out.Commit();
  return report;
}

}  // namespace skycal::color
