#include "skycal/capture/cloud_mask.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::capture {

bool CloudMaskOptions::IsValid(std::string* why) const {
  if (!(excess_cloud > excess_clear) || !std::isfinite(excess_clear) || !std::isfinite(excess_cloud)) {
    *why = "cloud mask: expected excess_cloud > excess_clear (finite)";
    return false;
  }
  if (!(sun_radius_deg >= 0.0 && sun_radius_deg <= 90.0) || !(sun_boost >= 0.0 && sun_boost <= 5.0)) {
    *why = "cloud mask: expected sun_radius_deg in [0, 90] and sun_boost in [0, 5]";
    return false;
  }
  if (!(offset_quantile >= 0.0 && offset_quantile <= 1.0) || !(max_offset >= 0.0 && max_offset <= 5.0)) {
    *why = "cloud mask: expected offset_quantile in [0, 1] and max_offset in [0, 5]";
    return false;
  }
  return true;
}

CloudMask EstimateCloudProbability(const ImageRGB& frame, const ImageRGB& clear, const std::optional<std::array<double, 3>>& sun,
                                   const CloudMaskOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (frame.width != clear.width || frame.height != clear.height) {
    throw Error("cloud mask: the clear-sky image is " + std::to_string(clear.width) + "x" + std::to_string(clear.height) +
                ", the frame " + std::to_string(frame.width) + "x" + std::to_string(frame.height));
  }
  const int w = frame.width, h = frame.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<float> excess(n, NAN), sun_weight(n, 0.0f);
  std::vector<double> away_from_sun;
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) <= 0.0) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float r = frame.pixels[3 * i], b = frame.pixels[3 * i + 2];
      const float rc = clear.pixels[3 * i], bc = clear.pixels[3 * i + 2];
      if (!(r > 0.0f && b > 0.0f && rc > 0.0f && bc > 0.0f) || !std::isfinite(r) || !std::isfinite(b)) continue;
      excess[i] = std::log(r / b) - std::log(rc / bc);
      double near = 0.0;
      if (sun && o.sun_radius_deg > 0.0) {
        const auto v = latlong::PixelDirection(x, y, w, h);
        const double angle =
            std::acos(std::clamp(v[0] * (*sun)[0] + v[1] * (*sun)[1] + v[2] * (*sun)[2], -1.0, 1.0)) * 180.0 / M_PI;
        near = std::max(0.0, 1.0 - angle / o.sun_radius_deg);
      }
      sun_weight[i] = static_cast<float>(near);
      if (near == 0.0) away_from_sun.push_back(excess[i]);
    }
  }
  CloudMask m;
  m.probability.assign(n, 0.0f);
  if (!away_from_sun.empty()) {
    const size_t k = static_cast<size_t>(o.offset_quantile * (away_from_sun.size() - 1));
    std::nth_element(away_from_sun.begin(), away_from_sun.begin() + k, away_from_sun.end());
    m.clear_offset = std::clamp(away_from_sun[k], -o.max_offset, o.max_offset);
  }
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(excess[i])) continue;
    const double d = excess[i] - m.clear_offset - o.sun_boost * sun_weight[i];
    const double t = std::clamp((d - o.excess_clear) / (o.excess_cloud - o.excess_clear), 0.0, 1.0);
    m.probability[i] = static_cast<float>(t * t * (3.0 - 2.0 * t));  // smoothstep
    m.cloudy_pixels += m.probability[i] >= 0.5f;
  }
  return m;
}

}  // namespace skycal::capture
