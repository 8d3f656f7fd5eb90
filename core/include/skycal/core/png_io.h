// PNG in and out through libpng (its simplified API), for every PNG skycal writes (previews,
// report panels, flow codes) or reads (the report's embedded images, bracket PNGs).
//
// Why not OpenCV's imgcodecs: on Debian it links GDAL and ~110 more libraries (poppler,
// HDF5, MariaDB, ...), and the dynamic loader then costs every skycal process ~0.1 s before
// main, twice for the verbs that re-execute for huge pages (huge_pages.h):
// bench/results/gpu_lavapipe.md, "Start-up".
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace skycal {

// An 8- or 16-bit raster, interleaved, rows packed: channels 1 (grey), 2 (grey, alpha),
// 3 (R, G, B) or 4 (R, G, B, A); 16-bit samples in the machine's byte order.
struct Raster {
  int width = 0;
  int height = 0;
  int channels = 0;
  int bits = 8;
  std::vector<uint8_t> data;  // width * height * channels * bits / 8 bytes

  Raster() = default;
  Raster(int w, int h, int c, int b);
  size_t row_bytes() const { return static_cast<size_t>(width) * channels * (bits / 8); }
  uint8_t* row(int y) { return data.data() + y * row_bytes(); }
  const uint8_t* row(int y) const { return data.data() + y * row_bytes(); }
  uint16_t* row16(int y) { return reinterpret_cast<uint16_t*>(row(y)); }
  const uint16_t* row16(int y) const { return reinterpret_cast<const uint16_t*>(row(y)); }
};

// Empty when a decoded image of width x height may be allocated; else why not. The
// decoders check the header's size before any pixel is allocated: at most 32768 a side and
// exr_io.h's pixel count (the fuzz build lowers it), so a damaged header cannot ask for
// gigabytes.
std::string RefusedImageSize(long long width, long long height);

// The PNG file's bytes. `compression`: zlib level 0-9 (6: zlib's default balance). Throws
// skycal::Error naming `what` (a path, for messages) on a malformed raster or a libpng error.
std::vector<uint8_t> EncodePng(const Raster& image, const std::string& what, int compression = 6);

// Decodes a PNG held in memory to its own channels (palette expanded, grey kept grey, an
// alpha channel kept) at 8 or 16 bits. Throws skycal::Error naming `what` when the bytes
// are not a PNG or do not decode (truncated, corrupt).
Raster DecodePng(const std::string& bytes, const std::string& what);

}  // namespace skycal
