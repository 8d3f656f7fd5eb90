#include "exposure.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/luminance.h"

namespace skycal::color::detail {

AutoExposure ComputeAutoExposure(const ImageRGB& linear) {
  AutoExposure out;
  double sum_log2 = 0.0;  // in double: a 4k image sums ~1e7 terms
  const size_t n = linear.pixels.size() / 3;
  for (size_t i = 0; i < n; ++i) {
    const float* p = &linear.pixels[i * 3];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    // Rec.709 / sRGB luminance weights (relative luminance of linear Rec.709 RGB).
    const double y = Rec709Luminance<double>(p[0], p[1], p[2]);
    if (!(y > 0.0)) continue;
    sum_log2 += std::log2(y);
    ++out.pixels_used;
  }
  if (out.pixels_used == 0) return out;  // nothing to measure: leave exposure at 0 EV
  const double mean_log2 = sum_log2 / static_cast<double>(out.pixels_used);
  out.log_average = std::exp2(mean_log2);
  out.ev = std::log2(kMidGrey) - mean_log2;
  return out;
}

size_t ExposeAndSanitize(ImageRGB& image, float scale) {
  size_t bad = 0;
  for (float& v : image.pixels) {
    if (std::isnan(v) || v < 0.0f) {  // -Inf lands here too
      v = 0.0f;
      ++bad;
      continue;
    }
    if (std::isinf(v)) ++bad;
    // inf * scale stays inf and finite * scale may overflow; min() catches both.
    v = std::min(v * scale, kMaxSceneValue);
  }
  return bad;
}

}  // namespace skycal::color::detail
