// A float RGB image, interleaved, row-major, row 0 at the top. Radiance values are
// linear in the project's working space (scene-linear Rec.709 primaries).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace skycal {

// The largest image skycal reads or writes: 32768 x 16384 (a 32K lat-long), 2^29 pixels,
// 6 GiB as float RGB. Checked against a file's header before anything is allocated, and
// against --size options before any work.
inline constexpr long long kMaxImageWidth = 32768, kMaxImageHeight = 16384;
inline constexpr long long kMaxImagePixels = kMaxImageWidth * kMaxImageHeight;

// Throws skycal::Error "<what>: W x H is larger than skycal's limit ..." (or non-positive).
void CheckImageSize(long long width, long long height, const std::string& what);

struct ImageRGB {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;  // width * height * 3 floats

  ImageRGB() = default;
  ImageRGB(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h * 3, 0.0f) {}

  size_t index(int x, int y) const { return (static_cast<size_t>(y) * width + x) * 3; }
  float& at(int x, int y, int c) { return pixels[index(x, y) + c]; }
  float at(int x, int y, int c) const { return pixels[index(x, y) + c]; }
  bool empty() const { return width <= 0 || height <= 0; }
};

}  // namespace skycal
