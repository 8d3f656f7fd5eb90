// RefineCoverageByLight (weather_inversion.h): coverage read from the lit image, per texel,
// by simultaneous random perturbation.
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

#include "lit_pixels_check.h"
#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/core/error.h"

namespace skycal::cloudfit {

bool CoverageLightOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& text) {
    if (why) *why = "CoverageLightOptions::" + text;
    return false;
  };
  if (iterations < 0 || iterations > 1000) return fail("iterations = " + std::to_string(iterations) + ": expected 0..1000");
  if (!(delta > 0.0 && delta <= 0.5)) return fail("delta = " + std::to_string(delta) + ": expected a coverage change in (0, 0.5]");
  if (!(max_step > 0.0 && max_step <= 1.0)) return fail("max_step = " + std::to_string(max_step) + ": expected (0, 1]");
  if (!(opacity_weight >= 0.0 && std::isfinite(opacity_weight)))
    return fail("opacity_weight = " + std::to_string(opacity_weight) + ": expected >= 0");
  return true;
}

namespace {

// The two residuals' RMS of `at` against the photo: ln Y where both have one, the opacity over
// every pixel the view links.
std::pair<double, double> Residuals(const WeatherTexelView& v, const LitPixels& photo, const LitPixels& at) {
  double sl = 0.0, nl = 0.0, so = 0.0, no = 0.0;
  for (size_t b = 0; b < v.rays.size(); ++b) {
    if (b > 0 && v.rays[b].pixel == v.rays[b - 1].pixel) continue;
    const size_t p = static_cast<size_t>(v.rays[b].pixel);
    const double ro = static_cast<double>(at.opacity[p]) - photo.opacity[p];
    so += ro * ro, no += 1.0;
    if (std::isfinite(at.log_luminance[p]) && std::isfinite(photo.log_luminance[p])) {
      const double rl = static_cast<double>(at.log_luminance[p]) - photo.log_luminance[p];
      sl += rl * rl, nl += 1.0;
    }
  }
  return {nl > 0.0 ? std::sqrt(sl / nl) : 0.0, no > 0.0 ? std::sqrt(so / no) : 0.0};
}

// The map stepped from `at` by each texel's Gauss-Newton step, its derivatives from `moved`
// (the map with each texel moved by sign x delta).
clouds::WeatherMap Stepped(const WeatherTexelView& v, const LitPixels& photo, const LitPixels& at, const LitPixels& moved,
                           const std::vector<float>& sign, const CoverageLightOptions& o, const clouds::WeatherMap& map) {
  const size_t n = v.linked.size();
  std::vector<double> num(n, 0.0), den(n, 0.0);
  for (const auto& s : v.rays) {
    const size_t p = static_cast<size_t>(s.pixel), t = static_cast<size_t>(s.texel);
    const double j_o = (static_cast<double>(moved.opacity[p]) - at.opacity[p]) / o.delta * sign[t];
    num[t] += o.opacity_weight * j_o * (static_cast<double>(at.opacity[p]) - photo.opacity[p]);
    den[t] += o.opacity_weight * j_o * j_o;
    const double l = at.log_luminance[p], lm = moved.log_luminance[p], lp = photo.log_luminance[p];
    if (std::isfinite(l) && std::isfinite(lm) && std::isfinite(lp)) {
      const double j_l = (lm - l) / o.delta * sign[t];
      num[t] += j_l * (l - lp);
      den[t] += j_l * j_l;
    }
  }
  clouds::WeatherMap next = map;
  for (size_t t = 0; t < n; ++t)
    if (den[t] > 0.0) {
      const double step = std::clamp(-num[t] / (den[t] + 1e-3), -o.max_step, o.max_step);
      next.rgb[3 * t] = static_cast<float>(std::clamp(map.rgb[3 * t] + step, 0.0, 1.0));
    }
  return next;
}

}  // namespace

CoverageLightResult RefineCoverageByLight(const WeatherTexelView& v, const LitPixels& photo,
                                          const std::function<LitPixels(const clouds::WeatherMap&)>& render,
                                          const CoverageLightOptions& o, clouds::WeatherMap* map) {
  std::string why;
  if (!o.IsValid(&why)) throw Error("RefineCoverageByLight: " + why);
  const size_t pixels = static_cast<size_t>(v.width) * v.height;
  CheckLitPixels(photo, pixels, "RefineCoverageByLight", "photo");
  LitPixels at = render(*map);
  CheckLitPixels(at, pixels, "RefineCoverageByLight", "the render");
  auto [log_rms, opacity_rms] = Residuals(v, photo, at);
  CoverageLightResult r{{log_rms}, {opacity_rms}, 0};
  std::mt19937 rng(o.seed);
  for (int it = 0; it < o.iterations; ++it) {
    std::vector<float> sign(v.linked.size(), 0.0f);
    clouds::WeatherMap moved = *map;
    for (size_t t = 0; t < sign.size(); ++t) {
      if (!v.linked[t]) continue;
      sign[t] = (rng() & 1u) ? 1.0f : -1.0f;
      moved.rgb[3 * t] = static_cast<float>(std::clamp(map->rgb[3 * t] + o.delta * sign[t], 0.0, 1.0));
    }
    clouds::WeatherMap next = Stepped(v, photo, at, render(moved), sign, o, *map);
    LitPixels stepped = render(next);
    const auto [l, op] = Residuals(v, photo, stepped);
    if (l * l + o.opacity_weight * op * op < log_rms * log_rms + o.opacity_weight * opacity_rms * opacity_rms) {
      *map = std::move(next), at = std::move(stepped), log_rms = l, opacity_rms = op;
      ++r.kept;
    }
    r.log_rms.push_back(log_rms);
    r.opacity_rms.push_back(opacity_rms);
  }
  return r;
}

}  // namespace skycal::cloudfit
