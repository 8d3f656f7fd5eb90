#include "skycal/cloudfit/photo_sun.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::cloudfit {

bool PhotoSunOptions::IsValid(std::string* why) const {
  if (!(disc_deg > 0.0 && disc_deg < ring_inner_deg && ring_inner_deg < ring_outer_deg && ring_outer_deg <= 45.0)) {
    *why = "photo sun: expected 0 < disc_deg < ring_inner_deg < ring_outer_deg <= 45 deg";
    return false;
  }
  if (!(clean_peak_over_background >= 1.0) || !(saturated_direct_to_diffuse >= 0.0)) {
    *why = "photo sun: expected clean_peak_over_background >= 1 and saturated_direct_to_diffuse >= 0";
    return false;
  }
  return true;
}

PhotoSun MeasurePhotoSun(const ImageRGB& img, const std::array<double, 3>& sun, const PhotoSunOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const double deg = M_PI / 180.0;
  const double cos_disc = std::cos(o.disc_deg * deg), cos_in = std::cos(o.ring_inner_deg * deg),
               cos_out = std::cos(o.ring_outer_deg * deg);
  struct Px {
    int x, y;
    double omega;
  };
  std::vector<Px> disc;
  std::vector<float> ring[3];
  double diffuse = 0.0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto v = latlong::PixelDirection(x, y, img.width, img.height);
      const double c = v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2];
      if (c >= cos_disc) {
        disc.push_back({x, y, latlong::PixelSolidAngle(x, y, img.width, img.height)});
        continue;
      }
      if (v[1] > 0.0) diffuse += img.at(x, y, 1) * v[1] * latlong::PixelSolidAngle(x, y, img.width, img.height);
      if (c <= cos_in && c >= cos_out) {
        for (int ch = 0; ch < 3; ++ch) ring[ch].push_back(img.at(x, y, ch));
      }
    }
  if (disc.empty() || ring[0].empty())
    throw Error("photo sun: the " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                " image has no pixel within " + std::to_string(o.disc_deg) + " deg of the sun or in its ring");
  PhotoSun s;
  for (int ch = 0; ch < 3; ++ch) {
    auto& r = ring[ch];
    std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
    s.background[ch] = r[r.size() / 2];
  }
  for (const Px& p : disc) {
    for (int ch = 0; ch < 3; ++ch) {
      s.illuminance[ch] += (img.at(p.x, p.y, ch) - s.background[ch]) * p.omega;
      s.peak = std::max(s.peak, static_cast<double>(img.at(p.x, p.y, ch)));
    }
  }
  s.disc_pixels = static_cast<int>(disc.size());
  s.direct_horizontal = s.illuminance[1] * std::max(sun[1], 0.0);
  s.diffuse_horizontal = diffuse;
  s.clean_peak_over_background = o.clean_peak_over_background;
  s.saturated_direct_to_diffuse = o.saturated_direct_to_diffuse;
  for (const Px& p : disc)
    for (int ch = 0; ch < 3; ++ch)
      if (img.at(p.x, p.y, ch) >= 0.999 * s.peak) {
        ++s.peak_pixels;
        break;
      }
  return s;
}

}  // namespace skycal::cloudfit
