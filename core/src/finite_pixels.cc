#include "skycal/core/finite_pixels.h"

#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/luminance.h"

namespace skycal {

void RequireValidShare(const std::string& path, long long valid, long long total, const std::string& what) {
  if (total > 0 && static_cast<double>(valid) >= kMinValidShare * static_cast<double>(total)) return;
  throw Error(path + ": only " + std::to_string(valid) + " of " + std::to_string(total) + " pixels are valid (" + what +
              "); at least " + FormatNumber(100.0 * kMinValidShare) +
              "% are needed: an all-NaN, all-zero or negative frame is not a usable sky");
}

void RequireValidShare(const std::string& path, const ImageRGB& image) {
  long long valid = 0;
  const long long n = static_cast<long long>(image.width) * image.height;
  for (long long i = 0; i < n; ++i) {
    const float* p = &image.pixels[3 * i];
    const bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    valid += finite && Rec709Luminance<double>(p[0], p[1], p[2]) > 0.0 ? 1 : 0;
  }
  RequireValidShare(path, valid, n, "every channel finite, luminance > 0");
}

FiniteOutputCounts MaskNonFinite(ImageRGB* image, bool half) {
  constexpr float kHalfMax = 65504.0f;  // IEEE 754 binary16's largest finite value
  FiniteOutputCounts n;
  for (float& v : image->pixels) {
    if (!std::isfinite(v)) {
      v = 0.0f;
      ++n.non_finite;
    } else if (half && std::abs(v) > kHalfMax) {
      ++n.half_clamped;
    }
  }
  return n;
}

}  // namespace skycal
