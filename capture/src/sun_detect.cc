#include "skycal/capture/sun_detect.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "latlong_blur.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/math_constants.h"
#include "skycal/core/latlong.h"

namespace skycal::capture {

std::optional<SunDetection> DetectSun(const ImageRGB& img, std::string* why, double min_contrast) {
  const int w = img.width, h = img.height;
  const int upper_rows = (h - 1) / 2 + 1;  // rows with latitude >= 0
  std::vector<double> lum;
  lum.reserve(static_cast<size_t>(w) * upper_rows);
  double peak = -1.0;
  int px = -1, py = -1;
  for (int y = 0; y < upper_rows; ++y) {
    for (int x = 0; x < w; ++x) {
      const float* p = &img.pixels[img.index(x, y)];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
      const double l = Luminance(p);
      if (!(l > 0.0)) continue;
      lum.push_back(l);
      if (l > peak) {
        peak = l;
        px = x;
        py = y;
      }
    }
  }
  if (px < 0) {
    *why = "no finite, positive pixel above the horizon";
    return std::nullopt;
  }
  std::nth_element(lum.begin(), lum.begin() + lum.size() / 2, lum.end());
  const double median = lum[lum.size() / 2];
  SunDetection d;
  d.peak_luminance = peak;
  d.contrast = peak / median;
  if (d.contrast < min_contrast) {
    *why = "brightest pixel is only " + FormatNumber(d.contrast) + "x the median sky luminance (need " +
           std::to_string(min_contrast) + "x for a distinct sun)";
    return std::nullopt;
  }
  // Region: pixels within 5 deg of the peak and at least half its luminance; centroid of
  // their directions weighted by solid angle x luminance.
  const auto peak_dir = latlong::PixelDirection(px, py, w, h);
  const double cos_limit = std::cos(5.0 * M_PI / 180.0);
  std::array<double, 3> sum{};
  int plateau = 0;
  for (int y = 0; y < upper_rows; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto v = latlong::PixelDirection(x, y, w, h);
      if (v[0] * peak_dir[0] + v[1] * peak_dir[1] + v[2] * peak_dir[2] < cos_limit) continue;
      const float* p = &img.pixels[img.index(x, y)];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
      const double l = Luminance(p);
      if (!(l >= 0.5 * peak)) continue;
      if (l >= peak * (1.0 - 1e-4)) ++plateau;
      const double wgt = latlong::PixelSolidAngle(x, y, w, h) * l;
      for (int k = 0; k < 3; ++k) sum[k] += wgt * v[k];
      ++d.region_pixels;
    }
  }
  d.direction = latlong::Normalized(sum, "sun centroid");
  d.clipped = plateau >= 3;
  return d;
}

std::optional<std::array<double, 3>> BrightestSkyPatch(const ImageRGB& img, const std::vector<float>& sky,
                                                       double sigma_deg, double min_elevation_deg) {
  const int w = img.width, h = img.height;
  if (sky.size() != static_cast<size_t>(w) * h)
    throw Error("BrightestSkyPatch: the sky mask has " + std::to_string(sky.size()) + " values for a " +
                std::to_string(w) + "x" + std::to_string(h) + " frame (expected one per pixel)");
  cv::Mat1f num(h, w, 0.0f), den(h, w, 0.0f);  // sky luminance and sky weight above the elevation
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) * 180.0 / kPi < min_elevation_deg) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const double Y = Luminance(&img.pixels[img.index(x, y)]);
      if (!(sky[i] >= 0.5f) || !(Y > 0.0) || !std::isfinite(Y)) continue;
      num(y, x) = static_cast<float>(Y);
      den(y, x) = 1.0f;
    }
  }
  const double sigma_px = sigma_deg / 360.0 * w;
  const cv::Mat1f bn = BlurWrapped(num, sigma_px), bd = BlurWrapped(den, sigma_px);
  int best_x = -1, best_y = -1;
  double best = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (den(y, x) > 0.0f && bd(y, x) >= 0.5f && bn(y, x) / bd(y, x) > best) {
        best = bn(y, x) / bd(y, x);
        best_x = x, best_y = y;
      }
  if (best_x < 0) return std::nullopt;
  return latlong::PixelDirection(best_x, best_y, w, h);
}

}  // namespace skycal::capture
