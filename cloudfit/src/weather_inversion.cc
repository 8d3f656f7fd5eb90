#include "skycal/cloudfit/weather_inversion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::cloudfit {

namespace {

constexpr int kLayerSamples = 4;  // altitudes per ray through the layer, at (k + 0.5) / kLayerSamples

// The pixel seeing the camera-relative point (x, y, z), or -1 (below the horizon, beyond the
// draw distance, not sky).
int PixelOf(double x, double y, double z, const clouds::CloudParams& p, int width, int height, const std::vector<float>& sky) {
  const double t = std::sqrt(x * x + y * y + z * z);
  if (y <= 0.0 || t > p.draw_distance_m) return -1;
  const auto pos = latlong::PixelPosition({x / t, y / t, z / t}, width, height);
  const int px = std::clamp(static_cast<int>(std::lround(pos[0])), 0, width - 1);
  const int py = std::clamp(static_cast<int>(std::lround(pos[1])), 0, height - 1);
  const int pix = py * width + px;
  return (!sky.empty() && !(sky[static_cast<size_t>(pix)] >= 0.5f)) ? -1 : pix;
}

// The texel under camera-relative (x, z), or -1 outside the map (it tiles beyond: those
// positions repeat texels nearer the camera, which are constrained directly).
int TexelOf(double x, double z, const clouds::CloudParams& p, int map_width, int map_height) {
  const double u = (x / p.weather_extent_m + 0.5) * map_width, v = (z / p.weather_extent_m + 0.5) * map_height;
  if (!(u >= 0.0 && u < map_width && v >= 0.0 && v < map_height)) return -1;
  return static_cast<int>(v) * map_width + static_cast<int>(u);
}

// Each texel's centre at the layer's mid altitude, to the pixel that sees it.
void LinkTexelCentres(const clouds::CloudParams& p, const std::vector<float>& sky, WeatherTexelView* v) {
  const double R = p.planet_radius_m, hc = p.camera_height_m;
  const double r_mid = R + 0.5 * (p.layer_bottom_m + p.layer_top_m);
  for (int j = 0; j < v->map_height; ++j)
    for (int i = 0; i < v->map_width; ++i) {
      const double x = ((i + 0.5) / v->map_width - 0.5) * p.weather_extent_m;
      const double z = ((j + 0.5) / v->map_height - 0.5) * p.weather_extent_m;
      if (x * x + z * z >= r_mid * r_mid) continue;
      const double y = std::sqrt(r_mid * r_mid - x * x - z * z) - (R + hc);
      const int pix = PixelOf(x, y, z, p, v->width, v->height, sky);
      if (pix >= 0) v->links.emplace_back(j * v->map_width + i, pix);
    }
}

// Each sky pixel's ray through the layer, to the texels under it.
void LinkPixelRays(const clouds::CloudParams& p, const std::vector<float>& sky, WeatherTexelView* v) {
  const double R = p.planet_radius_m, hc = p.camera_height_m;
  for (int py = 0; py < v->height; ++py)
    for (int px = 0; px < v->width; ++px) {
      const int pix = py * v->width + px;
      const latlong::Vec3d d = latlong::PixelDirection(px, py, v->width, v->height);
      if (d[1] <= 0.0 || (!sky.empty() && !(sky[static_cast<size_t>(pix)] >= 0.5f))) continue;
      for (int k = 0; k < kLayerSamples; ++k) {
        const double alt = p.layer_bottom_m + (k + 0.5) / kLayerSamples * (p.layer_top_m - p.layer_bottom_m);
        // Ray from the camera to the sphere of radius R + alt: t^2 + 2 b t - c' = 0 (the far root).
        const double b = (R + hc) * d[1], c = (alt - hc) * (2.0 * R + hc + alt);
        const double t = -b + std::sqrt(b * b + c);
        if (t > p.draw_distance_m) break;
        const int texel = TexelOf(t * d[0], t * d[2], p, v->map_width, v->map_height);
        if (texel >= 0) v->links.emplace_back(texel, pix);
      }
    }
}

}  // namespace

WeatherTexelView ProjectWeatherTexels(const clouds::CloudParams& p, int map_width, int map_height, int width, int height,
                                      const std::vector<float>& sky) {
  if (!sky.empty() && sky.size() != static_cast<size_t>(width) * height)
    throw Error("weather inversion: the sky mask has " + std::to_string(sky.size()) + " values, the photo " +
                std::to_string(static_cast<size_t>(width) * height) + " pixels");
  WeatherTexelView v{map_width, map_height, width, height, {}, 0};
  LinkTexelCentres(p, sky, &v);
  LinkPixelRays(p, sky, &v);
  std::sort(v.links.begin(), v.links.end());
  v.links.erase(std::unique(v.links.begin(), v.links.end()), v.links.end());
  for (size_t i = 0; i < v.links.size(); ++i) v.constrained += (i == 0 || v.links[i].first != v.links[i - 1].first);
  return v;
}

namespace {

// Per texel, the mean of `values` over its linked pixels (NaN where it has none).
std::vector<double> TexelMeans(const WeatherTexelView& v, const std::vector<double>& values) {
  std::vector<double> sum(static_cast<size_t>(v.map_width) * v.map_height, 0.0), n(sum.size(), 0.0);
  for (const auto& [texel, pix] : v.links) {
    sum[static_cast<size_t>(texel)] += values[static_cast<size_t>(pix)];
    n[static_cast<size_t>(texel)] += 1.0;
  }
  for (size_t t = 0; t < sum.size(); ++t) sum[t] = n[t] > 0.0 ? sum[t] / n[t] : std::numeric_limits<double>::quiet_NaN();
  return sum;
}

}  // namespace

void SeedCoverage(const WeatherTexelView& v, const std::vector<float>& opacity, double gain, clouds::WeatherMap* map) {
  const std::vector<double> mean = TexelMeans(v, std::vector<double>(opacity.begin(), opacity.end()));
  for (size_t t = 0; t < mean.size(); ++t)
    if (std::isfinite(mean[t])) map->rgb[3 * t] = static_cast<float>(std::clamp(gain * mean[t], 0.0, 1.0));
}

double RefineCoverage(const WeatherTexelView& v, const std::vector<float>& photo, const std::vector<float>& rendered,
                      double gain, clouds::WeatherMap* map) {
  std::vector<double> diff(photo.size(), 0.0);
  std::vector<char> linked(photo.size(), 0);
  for (size_t i = 0; i < diff.size(); ++i) diff[i] = static_cast<double>(rendered[i]) - photo[i];
  double sum = 0.0, n = 0.0;
  for (const auto& link : v.links) {
    const size_t pix = static_cast<size_t>(link.second);
    if (linked[pix]) continue;
    linked[pix] = 1;
    sum += diff[pix] * diff[pix];
    n += 1.0;
  }
  const std::vector<double> mean = TexelMeans(v, diff);
  for (size_t t = 0; t < mean.size(); ++t)
    if (std::isfinite(mean[t])) map->rgb[3 * t] = static_cast<float>(std::clamp(map->rgb[3 * t] - gain * mean[t], 0.0, 1.0));
  return n > 0.0 ? std::sqrt(sum / n) : 0.0;
}

std::vector<float> DownsampleLatLong(const std::vector<float>& values, int width, int height, int out_width, int out_height) {
  if (out_width <= 0 || out_height <= 0 || width % out_width != 0 || height % out_height != 0)
    throw Error("weather inversion: cannot box-average " + std::to_string(width) + "x" + std::to_string(height) + " to " +
                std::to_string(out_width) + "x" + std::to_string(out_height));
  const int fx = width / out_width, fy = height / out_height;
  std::vector<float> out(static_cast<size_t>(out_width) * out_height, 0.0f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      out[static_cast<size_t>(y / fy) * out_width + x / fx] += values[static_cast<size_t>(y) * width + x];
  for (float& o : out) o /= static_cast<float>(fx * fy);
  return out;
}

}  // namespace skycal::cloudfit
