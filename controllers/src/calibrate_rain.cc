// The light inside the recovered clouds: precipitation where the photo's clouds are darker than
// the game draws them (calibrate_weather.h, cloudfit::RefineByLight).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "calibrate_weather.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/game_clouds.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {
namespace {

// A texel counts as rained on in the decision when its precipitation rose by this much: the
// footprint smoothing spreads traces of a far texel's rain over many neighbours.
constexpr float kRaisedAtLeast = 0.01f;

// The pixels whose light is compared: sky, cloud in the photo (opacity >= 0.5), outside the
// sun's glare. (The game's side adds its own opacity >= 0.5: a pixel only one of them calls
// cloud is the opacity's business.)
std::vector<char> LightCounts(const PhotoWeatherView& v, const std::array<double, 3>& sun) {
  const double glare = std::cos(kSunGlareDeg * kRadiansPerDegree);
  std::vector<char> counts(v.opacity.size(), 0);
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      const size_t i = static_cast<size_t>(y) * v.width + x;
      const auto d = latlong::PixelDirection(x, y, v.width, v.height);
      counts[i] = v.sky[i] >= 0.5f && v.opacity[i] >= 0.5f && d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] < glare;
    }
  return counts;
}

// An image's pixels for the refinement: its opacity, and ln Y where `counts` and Y > 0.
cloudfit::LitPixels Lit(const ImageRGB& image, std::vector<float> opacity, const std::vector<char>& counts) {
  cloudfit::LitPixels p;
  p.opacity = std::move(opacity);
  p.log_luminance.assign(p.opacity.size(), std::numeric_limits<float>::quiet_NaN());
  for (size_t i = 0; i < p.opacity.size(); ++i) {
    if (!counts[i]) continue;
    const double y = Rec709Luminance<double>(image.pixels[3 * i], image.pixels[3 * i + 1], image.pixels[3 * i + 2]);
    if (y > 0.0) p.log_luminance[i] = static_cast<float>(std::log(y));
  }
  return p;
}

// The game's image at the view's size as the game composites it (clouds over the clear sky),
// in the photo's units (times the fit's exposure), as LitPixels: the fitted sky and lighting.
class LitGame {
 public:
  LitGame(const PhotoAnalysis& a, const PhotoWeatherView& v, const render::Preset& sky, const clouds::CloudParams& lit,
          double exposure, render::Backend backend)
      : preset_(sky),
        params_(lit),
        noise_(clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir())),
        renderer_(OpacityRenderer(backend)),
        exposure_(exposure),
        clear_(ClearSkyInPhotoUnits(a, preset_, exposure, v.width, v.height)) {
    request_.width = v.width;  // the game's march: its steps and light samples
    request_.height = v.height;
    request_.sun_dir = *a.sun.direction;
  }
  double weather_extent_m() const { return params_.weather_extent_m; }

  // ln Y where `counts` and the game's own opacity >= 0.5 (`cloud_only`), else where `counts`.
  cloudfit::LitPixels Render(const clouds::WeatherMap& map, std::vector<char> counts, bool cloud_only) {
    const clouds::CloudImage c = renderer_->Render({&preset_, &params_, noise_.get(), &map}, request_);
    ImageRGB g = clear_;
    std::vector<float> opacity(c.transmittance.size());
    for (size_t i = 0; i < opacity.size(); ++i) {
      const float t = c.transmittance[i];
      opacity[i] = 1.0f - t;
      if (cloud_only) counts[i] = counts[i] && t <= 0.5f;
      for (size_t k = 3 * i; k < 3 * i + 3; ++k)
        g.pixels[k] = static_cast<float>(clear_.pixels[k] * t + c.radiance.pixels[k] * exposure_);
    }
    return Lit(g, std::move(opacity), counts);
  }

 private:
  const render::Preset& preset_;
  const clouds::CloudParams& params_;
  std::shared_ptr<const clouds::CloudNoise> noise_;
  std::unique_ptr<clouds::CloudRenderer> renderer_;
  double exposure_;
  ImageRGB clear_;
  clouds::CloudRenderRequest request_;
};

// One step of precipitation on `map` (in place), then its coverage read from the light, and what
// they did.
PrecipitationRecord Rain(const PhotoAnalysis& a, const PhotoWeatherView& v, LitGame& game, clouds::WeatherMap* map) {
  const std::vector<char> counts = LightCounts(v, *a.sun.direction);
  const cloudfit::LitPixels photo = Lit(v.photo, v.opacity, counts);
  const cloudfit::LightRefineOptions o;
  const cloudfit::LitPixels at = game.Render(*map, counts, true);
  const cloudfit::LitPixels raised = game.Render(cloudfit::RaisedMap(v.texels, *map, o), counts, false);
  const std::vector<float> before = map->rgb;
  PrecipitationRecord r;
  r.step = cloudfit::RefineByLight(v.texels, photo, at, raised, o, map);
  // Resolved as the coverage is: far texels, crossed by few rays, follow their neighbours.
  cloudfit::SmoothChannelByFootprint(v.texels, game.weather_extent_m(), o.channel, map);
  double sum = 0.0;
  for (size_t t = 0; t < map->rgb.size(); t += 3)
    if (map->rgb[t + 1] - before[t + 1] >= kRaisedAtLeast) {
      sum += map->rgb[t + 1];
      r.max_raised = std::max(r.max_raised, static_cast<double>(map->rgb[t + 1]));
      ++r.raised_texels;
    }
  r.mean_raised = r.raised_texels > 0 ? sum / r.raised_texels : 0.0;
  r.width = v.width;
  r.coverage = cloudfit::RefineCoverageByLight(
      v.texels, photo, [&](const clouds::WeatherMap& m) { return game.Render(m, counts, false); }, {}, map);
  return r;
}

}  // namespace

std::optional<clouds::WeatherMap> RainFromTheLight::Refine(const render::Preset& sky, const clouds::CloudParams& lit,
                                                          double exposure, const clouds::WeatherMap& map) {
  const auto t0 = std::chrono::steady_clock::now();
  try {
    LitGame game(a_, view_, sky, lit, exposure, backend_);
    clouds::WeatherMap rained = map;
    record_ = Rain(a_, view_, game, &rained);
    record_->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rained;
  } catch (const std::exception& e) {  // the map stays as inverted, the lighting as the refit found it
    failure_ = std::string("the lit renders failed: ") + e.what();
    return std::nullopt;
  }
}

fit::FitDecision RainFromTheLight::Decision() const {
  const auto f3 = [](double x) { return FormatNumber(std::round(x * 1000.0) / 1000.0); };
  fit::FitDecision d;
  d.saved_ms_basis = "not measured in this run";
  if (!record_) {
    d.what = "precipitation: none read from the light";
    d.why = failure_ + "; the inverted map kept as it was";
    return d;
  }
  const PrecipitationRecord& r = *record_;
  d.what = "precipitation where the photo's clouds are darker than the game draws them, then their coverage from the light";
  d.why = std::to_string(r.step.pixels) + " cloud pixels compared (cloud in the photo and the game, outside " +
          FormatNumber(kSunGlareDeg) + " degrees of the sun): ln Y RMS " + f3(r.step.log_rms) +
          " under the refitted lighting; precipitation raised by " + FormatNumber(kRaisedAtLeast) + " or more in " +
          std::to_string(r.raised_texels) + " texels (mean " + f3(r.mean_raised) + ", at most " + f3(r.max_raised) +
          "): the game's rain absorption darkens a column with little change to where its cloud is; then the coverage "
          "texel by texel from the light (random perturbations tell a texel's own effect from its shadow on others', "
          "which one render with every texel raised cannot): ln Y RMS over the photo's cloud pixels " +
          f3(r.coverage.log_rms.front()) + " -> " + f3(r.coverage.log_rms.back()) + ", opacity RMS over the sky " +
          f3(r.coverage.opacity_rms.front()) + " -> " + f3(r.coverage.opacity_rms.back()) + ", " +
          std::to_string(r.coverage.kept) + " of " + std::to_string(r.coverage.log_rms.size() - 1) + " steps kept; " +
          std::to_string(2 + 2 * (r.coverage.log_rms.size() - 1) + 1) + " lit renders at " + std::to_string(r.width) +
          " px wide, " + FormatNumber(std::round(r.seconds * 100.0) / 100.0) + " s; the lighting solved on from there";
  return d;
}

}  // namespace skycal::controllers
