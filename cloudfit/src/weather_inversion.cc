#include "skycal/cloudfit/weather_inversion.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <thread>
#include <utility>

#include "lit_pixels_check.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal::cloudfit {

namespace {

// Rays are followed from this height fraction of the layer: below ~10% the march's bases are
// too thin to see (the height gradients rise over 8-15% and the bottoms' reduction over 20%).
constexpr double kBaseFraction = 0.1;
// The march's type blend cannot cut a column at any height: a type between stratus and
// cumulus keeps part of the cumulus gradient up to 70% of the layer. Only pure types cut:
// stratus is empty from 30% up, cumulus has fallen to 15% of its peak by 60% (its gradient
// falls from 40% to 70%).
constexpr double kCumulusClearFraction = 0.6;

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

// Texel (i, j)'s centre relative to a camera standing at `camera` on the map, m, at the
// texel's nearest copy (the map tiles).
std::array<double, 2> TexelFromCamera(int i, int j, int map_width, int map_height, double extent_m,
                                      const std::array<double, 2>& camera) {
  const auto nearest = [&](double m, double c) { return m - c - extent_m * std::round((m - c) / extent_m); };
  return {nearest(((i + 0.5) / map_width - 0.5) * extent_m, camera[0]),
          nearest(((j + 0.5) / map_height - 0.5) * extent_m, camera[1])};
}

// The texel under camera-relative (x, z) seen from `camera` (the wind's offset); the map tiles
// (the march's sampler wraps).
int TexelOf(double x, double z, const std::array<double, 2>& camera, const clouds::CloudParams& p, int map_width,
            int map_height) {
  x += camera[0], z += camera[1];
  const double u = (x / p.weather_extent_m + 0.5) * map_width, v = (z / p.weather_extent_m + 0.5) * map_height;
  const int i = static_cast<int>(std::floor(u)), j = static_cast<int>(std::floor(v));
  return ((j % map_height + map_height) % map_height) * map_width + ((i % map_width + map_width) % map_width);
}

// Each texel's centre at the layer's mid altitude, to the pixel that sees it (into `centres`).
void LinkTexelCentres(const clouds::CloudParams& p, const std::vector<float>& sky, WeatherTexelView* v,
                      std::vector<WeatherTexelView::RaySample>* centres) {
  const double R = p.planet_radius_m, hc = p.camera_height_m;
  const double r_mid = R + 0.5 * (p.layer_bottom_m + p.layer_top_m);
  for (int j = 0; j < v->map_height; ++j)
    for (int i = 0; i < v->map_width; ++i) {
      const auto [x, z] = TexelFromCamera(i, j, v->map_width, v->map_height, p.weather_extent_m, v->cameras[0]);
      if (x * x + z * z >= r_mid * r_mid) continue;
      const double y = std::sqrt(r_mid * r_mid - x * x - z * z) - (R + hc);
      const int pix = PixelOf(x, y, z, p, v->width, v->height, sky);
      if (pix >= 0) centres->push_back({pix, j * v->map_width + i, 0.5f});
    }
}

// The distance along direction d (unit, camera-relative) to the sphere of radius R + alt.
double DistanceToAltitude(const clouds::CloudParams& p, const latlong::Vec3d& d, double alt) {
  const double R = p.planet_radius_m, hc = p.camera_height_m;
  // |c + t d| = R + alt with c = (0, R + hc, 0): t^2 + 2 b t - c' = 0 (the far root).
  const double b = (R + hc) * d[1], c = (alt - hc) * (2.0 * R + hc + alt);
  return -b + std::sqrt(b * b + c);
}

// Where a ray (unit direction d, upward) samples the layer: from kBaseFraction of it to its
// top or the draw distance, in steps of half a texel across and an eighth of the layer up.
struct RaySpan {
  double t0 = 0.0, t1 = 0.0, step = 1.0;  // m along the ray
};
RaySpan SpanThroughLayer(const clouds::CloudParams& p, const WeatherTexelView& v, const latlong::Vec3d& d) {
  const double thick = p.layer_top_m - p.layer_bottom_m, texel_m = p.weather_extent_m / v.map_width;
  RaySpan s;
  s.t0 = DistanceToAltitude(p, d, p.layer_bottom_m + kBaseFraction * thick);
  s.t1 = std::min(DistanceToAltitude(p, d, p.layer_top_m), p.draw_distance_m);
  const double cos_el = std::sqrt(std::max(0.0, 1.0 - d[1] * d[1]));
  s.step = std::min(0.5 * texel_m / std::max(cos_el, 1e-3), thick / 8.0 / std::max(d[1], 1e-3));
  return s;
}

void LinkPixelRows(const clouds::CloudParams& p, const std::vector<float>& sky, const WeatherTexelView& v, int row0,
                   int row1, std::vector<WeatherTexelView::RaySample>* out) {
  const double R = p.planet_radius_m, hc = p.camera_height_m, thick = p.layer_top_m - p.layer_bottom_m;
  for (int py = row0; py < row1; ++py)
    for (int px = 0; px < v.width; ++px) {
      const int pix = py * v.width + px;
      const latlong::Vec3d d = latlong::PixelDirection(px, py, v.width, v.height);
      if (d[1] <= 0.0 || (!sky.empty() && !(sky[static_cast<size_t>(pix)] >= 0.5f))) continue;
      const RaySpan span = SpanThroughLayer(p, v, d);
      int last = -1;
      for (double t = span.t0; t <= span.t1; t += span.step) {
        const int texel = TexelOf(t * d[0], t * d[2], v.cameras[0], p, v.map_width, v.map_height);
        if (texel == last) continue;
        last = texel;
        const double x = t * d[0], y = R + hc + t * d[1], z = t * d[2];
        const double f = (std::sqrt(x * x + y * y + z * z) - R - p.layer_bottom_m) / thick;
        out->push_back({pix, texel, static_cast<float>(f)});
      }
    }
}

// The row splitting the rays' samples in two about equal halves (a row's rays all have its
// elevation: their samples along the layer grow toward the horizon).
int MiddleRow(const clouds::CloudParams& p, const WeatherTexelView& v, int rows, double* samples) {
  std::vector<double> cost(static_cast<size_t>(rows), 0.0);
  for (int py = 0; py < rows; ++py) {
    const latlong::Vec3d d = latlong::PixelDirection(0, py, v.width, v.height);
    if (d[1] <= 0.0) continue;
    const RaySpan span = SpanThroughLayer(p, v, d);
    cost[static_cast<size_t>(py)] = std::max(0.0, span.t1 - span.t0) / span.step + 1.0;
  }
  const double total = std::accumulate(cost.begin(), cost.end(), 0.0);
  *samples = total * v.width;  // an upper bound: repeated texels are skipped
  double sum = 0.0;
  for (int py = 0; py < rows; ++py)
    if ((sum += cost[static_cast<size_t>(py)]) >= 0.5 * total) return py + 1;
  return rows;
}

// Each sky pixel's ray through the layer, front to back, to every texel under it (steps of
// half a texel across and an eighth of the layer up; the map wraps as the march's sampler
// does), in pixel order: two threads take the rows of the upper hemisphere in two halves of
// about equal work.
void LinkPixelRays(const clouds::CloudParams& p, const std::vector<float>& sky, WeatherTexelView* v) {
  double samples = 0.0;
  const int upper = (v->height + 1) / 2, mid = MiddleRow(p, *v, upper, &samples);
  std::vector<WeatherTexelView::RaySample> second;
  second.reserve(static_cast<size_t>(0.5 * samples));
  v->rays.reserve(static_cast<size_t>(samples) + static_cast<size_t>(v->map_width) * v->map_height);
  std::thread worker([&] { LinkPixelRows(p, sky, *v, mid, upper, &second); });
  LinkPixelRows(p, sky, *v, 0, mid, &v->rays);
  worker.join();
  v->rays.insert(v->rays.end(), second.begin(), second.end());
}

}  // namespace

WeatherTexelView ProjectWeatherTexels(const clouds::CloudParams& p, int map_width, int map_height, int width, int height,
                                      const std::vector<float>& sky, double time_s) {
  if (!sky.empty() && sky.size() != static_cast<size_t>(width) * height)
    throw Error("weather inversion: the sky mask has " + std::to_string(sky.size()) + " values, the photo " +
                std::to_string(static_cast<size_t>(width) * height) + " pixels");
  WeatherTexelView v{map_width, map_height, width, height, {}, 0, {}, {clouds::WindOffsetM(p, time_s)}};
  // The rays come out grouped by pixel in order, each front to back (the height rises along
  // a ray); the centre links are sorted alone and merged in (a sort of the millions of
  // samples at 512 pixels cost more than the renders).
  std::vector<WeatherTexelView::RaySample> centres, rays;
  LinkTexelCentres(p, sky, &v, &centres);
  LinkPixelRays(p, sky, &v);
  const auto order = [](const auto& a, const auto& b) {
    return a.pixel != b.pixel ? a.pixel < b.pixel : a.fraction < b.fraction;
  };
  std::sort(centres.begin(), centres.end(), order);
  rays.reserve(v.rays.size() + centres.size());
  std::merge(v.rays.begin(), v.rays.end(), centres.begin(), centres.end(), std::back_inserter(rays), order);
  v.rays = std::move(rays);
  v.linked.assign(static_cast<size_t>(map_width) * map_height, 0);
  for (const auto& s : v.rays) v.linked[static_cast<size_t>(s.texel)] = 1;
  v.constrained = static_cast<int>(std::count(v.linked.begin(), v.linked.end(), 1));
  return v;
}

WeatherTexelView StackWeatherViews(const std::vector<WeatherTexelView>& views) {
  if (views.empty()) throw Error("StackWeatherViews: no view given; expected one per frame");
  const WeatherTexelView& a = views.front();
  WeatherTexelView out{a.map_width, a.map_height, a.width, 0, std::vector<char>(a.linked.size(), 0), 0, {}, {}};
  for (size_t k = 0; k < views.size(); ++k) {
    const WeatherTexelView& v = views[k];
    if (v.map_width != a.map_width || v.map_height != a.map_height || v.width != a.width || v.height != a.height)
      throw Error("StackWeatherViews: frame " + std::to_string(k) + " views a " + std::to_string(v.map_width) + "x" +
                  std::to_string(v.map_height) + " map from " + std::to_string(v.width) + "x" + std::to_string(v.height) +
                  " pixels; expected frame 0's " + std::to_string(a.map_width) + "x" + std::to_string(a.map_height) +
                  " from " + std::to_string(a.width) + "x" + std::to_string(a.height));
    const int first = out.height * out.width;  // frame k's pixel 0
    for (WeatherTexelView::RaySample s : v.rays) {
      s.pixel += first;
      out.rays.push_back(s);
    }
    for (size_t t = 0; t < v.linked.size(); ++t) out.linked[t] |= v.linked[t];
    out.cameras.insert(out.cameras.end(), v.cameras.begin(), v.cameras.end());
    out.height += v.height;
  }
  out.constrained = static_cast<int>(std::count(out.linked.begin(), out.linked.end(), 1));
  return out;
}

double CloudTypeForTop(double top) { return top >= kCumulusClearFraction ? 0.5 : 0.0; }

namespace {

// The height fraction up to which a texel of this type holds cloud (CloudTypeForTop's inverse).
double TopForType(double type) { return type >= 0.25 ? kCumulusClearFraction : 0.3; }

}  // namespace

void CarveCoverage(const WeatherTexelView& v, const std::vector<float>& opacity, const CarveOptions& o,
                   clouds::WeatherMap* map) {
  const size_t n = static_cast<size_t>(v.map_width) * v.map_height;
  std::vector<double> lowest(n, std::numeric_limits<double>::infinity()), top(n, o.cumulus_top);
  std::vector<double> lowest_high(n, std::numeric_limits<double>::infinity());  // below fallback_top
  const std::vector<char>& seen = v.linked;
  for (const auto& s : v.rays) {
    const size_t t = static_cast<size_t>(s.texel);
    const double op = opacity[static_cast<size_t>(s.pixel)];
    if (s.fraction <= o.base_top) lowest[t] = std::min(lowest[t], op);
    else if (s.fraction <= o.fallback_top) lowest_high[t] = std::min(lowest_high[t], op);
    if (op < o.clear_opacity) top[t] = std::min(top[t], static_cast<double>(s.fraction));
  }
  for (size_t t = 0; t < n; ++t) {
    if (!seen[t]) continue;
    // Crossed only above the base: what it holds there is unseen; the statistics' coverage stays.
    if (!std::isfinite(lowest[t])) lowest[t] = lowest_high[t];  // crossed only higher up
    if (std::isfinite(lowest[t])) map->rgb[3 * t] = static_cast<float>(std::clamp(o.gain * lowest[t], 0.0, 1.0));
    map->rgb[3 * t + 1] = 0.0f;
    map->rgb[3 * t + 2] = static_cast<float>(CloudTypeForTop(top[t]));
  }
}

double RefineCoverage(const WeatherTexelView& v, const std::vector<float>& photo, const std::vector<float>& rendered,
                      double gain, clouds::WeatherMap* map) {
  const size_t n = static_cast<size_t>(v.map_width) * v.map_height;
  std::vector<double> sum(n, 0.0), count(n, 0.0);
  double sq = 0.0, pixels = 0.0;
  for (size_t b = 0; b < v.rays.size();) {  // one pixel's ray: samples b .. e - 1
    size_t e = b;
    while (e < v.rays.size() && v.rays[e].pixel == v.rays[b].pixel) ++e;
    const size_t pix = static_cast<size_t>(v.rays[b].pixel);
    const double r = static_cast<double>(rendered[pix]) - photo[pix];
    sq += r * r;
    pixels += 1.0;
    for (size_t i = b; i < e; ++i) {
      const size_t t = static_cast<size_t>(v.rays[i].texel);
      if (v.rays[i].fraction > TopForType(map->rgb[3 * t + 2])) continue;  // above the texel's cloud top
      sum[t] -= r;
      count[t] += 1.0;
    }
    b = e;
  }
  for (size_t t = 0; t < n; ++t)
    if (count[t] > 0.0) map->rgb[3 * t] = static_cast<float>(std::clamp(map->rgb[3 * t] + gain * sum[t] / count[t], 0.0, 1.0));
  return pixels > 0.0 ? std::sqrt(sq / pixels) : 0.0;
}

bool LightRefineOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& text) {
    if (why) *why = "LightRefineOptions::" + text;
    return false;
  };
  if (channel != 0 && channel != 1) return fail("channel = " + std::to_string(channel) + ": expected 0 (coverage) or 1 (precipitation)");
  if (!(delta > 0.0 && delta <= 1.0)) return fail("delta = " + std::to_string(delta) + ": expected a raise in (0, 1]");
  if (!(max_step > 0.0 && max_step <= 1.0)) return fail("max_step = " + std::to_string(max_step) + ": expected (0, 1]");
  if (!(damping > 0.0 && std::isfinite(damping))) return fail("damping = " + std::to_string(damping) + ": expected > 0");
  if (pixel_radius < 0 || pixel_radius > 16) return fail("pixel_radius = " + std::to_string(pixel_radius) + ": expected 0..16");
  return true;
}

clouds::WeatherMap RaisedMap(const WeatherTexelView& v, const clouds::WeatherMap& map, const LightRefineOptions& o) {
  clouds::WeatherMap out = map;
  for (size_t t = 0; t < v.linked.size(); ++t)
    if (v.linked[t]) {
      float& c = out.rgb[3 * t + static_cast<size_t>(o.channel)];
      c = static_cast<float>(std::min(1.0, c + o.delta));
    }
  return out;
}

namespace {

// One pixel's Gauss-Newton step in the channel on its opacity and log-luminance residuals,
// the derivatives the difference of the two renders over delta; the luminance residual's
// square added to *sq (and 1 to *n) where it counts.
double PixelStep(size_t p, const LitPixels& photo, const LitPixels& at, const LitPixels& raised,
                 const LightRefineOptions& o, double* sq, double* n) {
  const double r_o = static_cast<double>(at.opacity[p]) - photo.opacity[p];
  const double j_o = (static_cast<double>(raised.opacity[p]) - at.opacity[p]) / o.delta;
  double num = j_o * r_o, den = j_o * j_o + o.damping;
  const double l = at.log_luminance[p], lp = photo.log_luminance[p], lr = raised.log_luminance[p];
  if (std::isfinite(l) && std::isfinite(lp)) {
    const double r_l = l - lp;
    *sq += r_l * r_l;
    *n += 1.0;
    if (std::isfinite(lr)) {
      const double j_l = (lr - l) / o.delta;
      num += j_l * r_l;
      den += j_l * j_l;
    }
  }
  return std::clamp(-num / den, -o.max_step, o.max_step);
}

// Each pixel's step as the mean of the steps within `radius` pixels (the lat-long wraps in x),
// pixels without one (NaN) left out and left without.
std::vector<double> SmoothSteps(const std::vector<double>& steps, int width, int height, int radius) {
  if (radius <= 0) return steps;
  std::vector<double> out(steps.size(), std::numeric_limits<double>::quiet_NaN());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (std::isnan(steps[static_cast<size_t>(y) * width + x])) continue;
      double sum = 0.0, n = 0.0;
      for (int j = std::max(0, y - radius); j <= std::min(height - 1, y + radius); ++j)
        for (int i = x - radius; i <= x + radius; ++i) {
          const double s = steps[static_cast<size_t>(j) * width + static_cast<size_t>((i + width) % width)];
          if (!std::isnan(s)) sum += s, n += 1.0;
        }
      out[static_cast<size_t>(y) * width + x] = sum / n;
    }
  return out;
}

}  // namespace

LightRefineStep RefineByLight(const WeatherTexelView& v, const LitPixels& photo, const LitPixels& at,
                              const LitPixels& raised, const LightRefineOptions& o, clouds::WeatherMap* map) {
  std::string why;
  if (!o.IsValid(&why)) throw Error("RefineByLight: " + why);
  const size_t pixels = static_cast<size_t>(v.width) * v.height, n = static_cast<size_t>(v.map_width) * v.map_height;
  CheckLitPixels(photo, pixels, "RefineByLight", "photo");
  CheckLitPixels(at, pixels, "RefineByLight", "at");
  CheckLitPixels(raised, pixels, "RefineByLight", "raised");
  std::vector<double> steps(pixels, std::numeric_limits<double>::quiet_NaN());
  double sq = 0.0, counted = 0.0;
  for (size_t b = 0; b < v.rays.size(); ++b)
    if (b == 0 || v.rays[b].pixel != v.rays[b - 1].pixel) {
      const size_t p = static_cast<size_t>(v.rays[b].pixel);
      steps[p] = PixelStep(p, photo, at, raised, o, &sq, &counted);
    }
  steps = SmoothSteps(steps, v.width, v.height, o.pixel_radius);
  std::vector<double> sum(n, 0.0), count(n, 0.0);
  for (const auto& s : v.rays) {
    const size_t t = static_cast<size_t>(s.texel);
    if (s.fraction > TopForType(map->rgb[3 * t + 2])) continue;  // above the texel's cloud top
    sum[t] += steps[static_cast<size_t>(s.pixel)];
    count[t] += 1.0;
  }
  LightRefineStep r;
  for (size_t t = 0; t < n; ++t) {
    if (count[t] == 0.0) continue;
    float& c = map->rgb[3 * t + static_cast<size_t>(o.channel)];
    const float next = static_cast<float>(std::clamp(c + sum[t] / count[t], 0.0, 1.0));
    r.texels_moved += std::abs(next - c) > 1e-3f;
    c = next;
  }
  r.pixels = static_cast<int>(counted);
  r.log_rms = counted > 0.0 ? std::sqrt(sq / counted) : 0.0;
  return r;
}

namespace {

// Texel (i, j)'s horizontal distance to the nearest of the view's cameras, m (the map wraps).
double NearestCamera(const WeatherTexelView& v, double extent_m, int i, int j) {
  if (v.cameras.empty()) {  // a view built by hand: the camera at the map's centre
    const auto [x, z] = TexelFromCamera(i, j, v.map_width, v.map_height, extent_m, {0.0, 0.0});
    return std::hypot(x, z);
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& c : v.cameras) {
    const auto [x, z] = TexelFromCamera(i, j, v.map_width, v.map_height, extent_m, c);
    best = std::min(best, std::hypot(x, z));
  }
  return best;
}

}  // namespace

void SmoothCoverageByFootprint(const WeatherTexelView& v, double extent_m, clouds::WeatherMap* map) {
  SmoothChannelByFootprint(v, extent_m, 0, map);
}

void SmoothChannelByFootprint(const WeatherTexelView& v, double extent_m, int channel, clouds::WeatherMap* map) {
  const int W = v.map_width, H = v.map_height;
  const std::vector<char>& constrained = v.linked;
  const double texel_m = extent_m / W, pixel_rad = 2.0 * kPi / v.width;
  std::vector<float> out(map->rgb);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      if (!constrained[static_cast<size_t>(j) * W + i]) continue;
      const double d = NearestCamera(v, extent_m, i, j);
      const int k = static_cast<int>(0.5 * d * pixel_rad / texel_m);
      if (k < 1) continue;
      double sum = 0.0, n = 0.0;
      for (int y = std::max(0, j - k); y <= std::min(H - 1, j + k); ++y)
        for (int x = std::max(0, i - k); x <= std::min(W - 1, i + k); ++x)
          if (constrained[static_cast<size_t>(y) * W + x]) {
            sum += map->rgb[3 * (static_cast<size_t>(y) * W + x) + static_cast<size_t>(channel)];
            n += 1.0;
          }
      out[3 * (static_cast<size_t>(j) * W + i) + static_cast<size_t>(channel)] = static_cast<float>(sum / n);
    }
  map->rgb = std::move(out);
}

std::vector<double> InvertWeatherMap(const WeatherTexelView& view, double extent_m, const std::vector<float>& photo,
                                     const std::function<std::vector<float>(const clouds::WeatherMap&)>& render_opacity,
                                     const InversionOptions& o, clouds::WeatherMap* map) {
  CarveCoverage(view, photo, o.carve, map);
  SmoothCoverageByFootprint(view, extent_m, map);
  std::vector<double> rms;
  for (int k = 0; k < o.refinements; ++k) {
    rms.push_back(RefineCoverage(view, photo, render_opacity(*map), o.step, map));
    SmoothCoverageByFootprint(view, extent_m, map);
  }
  return rms;
}

}  // namespace skycal::cloudfit
