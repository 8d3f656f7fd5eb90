#include "image_compare.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "skycal/core/latlong.h"

namespace skycal::bench {
namespace {

// Bilinear sample at a continuous pixel position of the node-centred grid (core/latlong.h:
// x in [0, W-1], the seam stored twice, so no wrap is needed).
void Sample(const ImageRGB& im, double x, double y, double out[3]) {
  x = std::clamp(x, 0.0, im.width - 1.0);
  y = std::clamp(y, 0.0, im.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), im.width - 2), y0 = std::min(static_cast<int>(y), im.height - 2);
  const double fx = x - x0, fy = y - y0;
  for (int c = 0; c < 3; ++c) {
    const double top = (1 - fx) * im.at(x0, y0, c) + fx * im.at(x0 + 1, y0, c);
    const double bottom = (1 - fx) * im.at(x0, y0 + 1, c) + fx * im.at(x0 + 1, y0 + 1, c);
    out[c] = (1 - fy) * top + fy * bottom;
  }
}

}  // namespace

ImageRGB AreaMeanAtNodes(const ImageRGB& fine, int width, int height) {
  std::vector<double> sum(static_cast<size_t>(width) * height * 3, 0.0), weight(static_cast<size_t>(width) * height, 0.0);
  for (int y = 0; y < fine.height; ++y)
    for (int x = 0; x < fine.width; ++x) {
      const auto pos = latlong::PixelPosition(latlong::PixelDirection(x, y, fine.width, fine.height), width, height);
      int nx = static_cast<int>(std::lround(pos[0]));
      const int ny = std::clamp(static_cast<int>(std::lround(pos[1])), 0, height - 1);
      if (nx >= width - 1) nx = 0;  // the seam: column W-1 repeats column 0
      const double w = latlong::PixelSolidAngle(x, y, fine.width, fine.height);
      const size_t i = static_cast<size_t>(ny) * width + std::clamp(nx, 0, width - 1);
      for (int c = 0; c < 3; ++c) sum[3 * i + c] += w * fine.at(x, y, c);
      weight[i] += w;
    }
  ImageRGB out(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + (x == width - 1 ? 0 : x);
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = weight[i] > 0.0 ? static_cast<float>(sum[3 * i + c] / weight[i]) : 0.0f;
    }
  return out;
}

bool AllFinite(const ImageRGB& image) {
  return std::all_of(image.pixels.begin(), image.pixels.end(), [](float v) { return std::isfinite(v); });
}

double RelRmse(const ImageRGB& truth, const ImageRGB& image, double min_elevation_deg, bool fit_scale) {
  if (truth.empty() || image.empty()) return std::nan("");
  struct Px {
    double t[3], v[3], w;
  };
  std::vector<Px> px;
  if (image.width < 2 || image.height < 2) return std::nan("");
  for (int y = 0; y < truth.height; ++y) {
    const double lat_deg = latlong::Latitude(y, truth.height) * 180.0 / M_PI;
    if (lat_deg <= min_elevation_deg) continue;
    for (int x = 0; x < truth.width; ++x) {
      Px p;
      p.w = latlong::PixelSolidAngle(x, y, truth.width, truth.height);
      const auto pos = latlong::PixelPosition(latlong::PixelDirection(x, y, truth.width, truth.height), image.width, image.height);
      Sample(image, pos[0], pos[1], p.v);
      bool ok = true;
      for (int c = 0; c < 3; ++c) {
        p.t[c] = truth.at(x, y, c);
        ok = ok && std::isfinite(p.t[c]) && p.t[c] > 0.0 && std::isfinite(p.v[c]) && p.v[c] > 0.0;
      }
      if (ok) px.push_back(p);
    }
  }
  if (px.empty()) return std::nan("");
  double scale = 1.0;
  if (fit_scale) {
    std::vector<double> ratio;
    for (const Px& p : px)
      for (int c = 0; c < 3; ++c) ratio.push_back(p.t[c] / p.v[c]);
    std::nth_element(ratio.begin(), ratio.begin() + ratio.size() / 2, ratio.end());
    scale = ratio[ratio.size() / 2];
  }
  double sum = 0.0, wsum = 0.0;
  for (const Px& p : px)
    for (int c = 0; c < 3; ++c) {
      const double r = (scale * p.v[c] - p.t[c]) / p.t[c];
      sum += p.w * r * r;
      wsum += p.w;
    }
  return std::sqrt(sum / wsum);
}

}  // namespace skycal::bench
