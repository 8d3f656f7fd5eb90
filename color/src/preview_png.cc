// Writes a display preview as an 8-bit PNG, atomically.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>

#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/png_io.h"
#include "skycal/core/output_kind.h"

namespace skycal::color {
namespace {

// PNG bytes for an interleaved 8-bit RGB buffer. Compression level 6: zlib's default
// balance; previews are written once, read often.
std::vector<uint8_t> EncodePng(std::vector<uint8_t> rgb, int width, int height, const std::string& path) {
  Raster r;
  r.width = width;
  r.height = height;
  r.channels = 3;
  r.data = std::move(rgb);
  return skycal::EncodePng(r, path, 6);
}

}  // namespace

PreviewReport WritePreviewPng(const ImageRGB& linear, const std::string& png_path, const PreviewOptions& options) {
  // Check the destination first (cheap, and AtomicOutput's errors name the path).
  RefuseMismatchedExtension(png_path, ".png", "a PNG preview");
  AtomicOutput out(png_path);
  PreviewReport report;
  std::vector<uint8_t> png;
  try {
    png = EncodePng(ToDisplay8(linear, options, &report), linear.width, linear.height, png_path);
  } catch (const Error& e) {
    throw Error(png_path + ": " + e.what());
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
