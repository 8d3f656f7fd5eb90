#include "pyramid.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/latlong.h"

namespace skycal::fit {

FitLevel BuildLevel(const Reference& ref, int width) {
  const int W = ref.radiance.width, H = ref.radiance.height;
  FitLevel level;
  level.width = std::min(width, W);
  level.height = level.width / 2;
  if (level.width == W) level.height = H;  // the reference itself (2:1 checked at load)
  const int w = level.width, h = level.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> sum(3 * n, 0.0), fitted(n, 0.0), assigned(n, 0.0);
  for (int y = 0; y < H; ++y) {
    const int cy = static_cast<int>(std::lround(static_cast<double>(y) * (h - 1) / (H - 1)));
    for (int x = 0; x < W; ++x) {
      const int cx = static_cast<int>(std::lround(static_cast<double>(x) * (w - 1) / (W - 1)));
      const size_t ci = static_cast<size_t>(cy) * w + cx;
      const double omega = latlong::PixelSolidAngle(x, y, W, H);
      assigned[ci] += omega;
      const size_t fi = static_cast<size_t>(y) * W + x;
      if (ref.pixel_class[fi] != PixelClass::kSky) continue;
      fitted[ci] += omega;
      for (int c = 0; c < 3; ++c) sum[3 * ci + c] += omega * ref.radiance.pixels[3 * fi + c];
    }
  }
  level.radiance.assign(3 * n, 0.0f);
  level.weight.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    // The node must be above the horizon too: the model is evaluated at the node.
    const int y = static_cast<int>(i / w);
    if (fitted[i] <= 0.0 || fitted[i] < 0.5 * assigned[i] || latlong::Latitude(y, h) <= 0.0) continue;
    level.weight[i] = fitted[i];
    level.total_weight += fitted[i];
    for (int c = 0; c < 3; ++c) level.radiance[3 * i + c] = static_cast<float>(sum[3 * i + c] / fitted[i]);
  }
  return level;
}

std::vector<int> AutomaticPyramid(int reference_width) {
  const int top = std::min(reference_width, 512);
  std::vector<int> widths;
  for (int w = 64; w < top; w *= 2) widths.push_back(w);
  widths.push_back(top);
  return widths;
}

}  // namespace skycal::fit
