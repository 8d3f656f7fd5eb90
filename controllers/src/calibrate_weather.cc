#include "calibrate_weather.h"

#include <chrono>
#include <filesystem>

#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {
namespace {

constexpr int kRenderWidth = 256;   // the refinement renders (pixels): a texel near the zenith is ~1 pixel at 512
constexpr int kRefinements = 3;     // renders; each moves every constrained texel toward the photo
// Coverage per unit opacity error: the march's opacity grows about twice as fast as the mean
// coverage at partly cloudy coverages (the statistics fit's matched coverage steps, fit.json).
constexpr double kStep = 0.5;

// The statistics fit's coverage per unit of photo cloud probability (its matched mean
// coverage over the photo's mean probability), the first guess's gain.
double SeedGain(const std::string& fit_json) {
  const nlohmann::json cs = fit::ReadFitResultFile(fit_json).cloud_stats;
  const auto c = cs.is_object() ? cs.find("coverage") : cs.end();
  if (c != cs.end() && c->is_object() && c->contains("matched_mean_coverage") && c->contains("photo_mean_cloud_probability")) {
    const double p = (*c)["photo_mean_cloud_probability"].get<double>();
    if (p > 1e-3) return std::clamp((*c)["matched_mean_coverage"].get<double>() / p, 0.1, 2.0);
  }
  return kStep;
}

std::vector<float> Opacity(const std::vector<float>& transmittance) {
  std::vector<float> o(transmittance.size());
  for (size_t i = 0; i < o.size(); ++i) o[i] = 1.0f - transmittance[i];
  return o;
}

}  // namespace

fit::FitDecision WeatherInversionRecord::Decision() const {
  fit::FitDecision d;
  d.saved_ms_basis = "not measured in this run";
  if (!done) {
    d.what = "weather map: the statistical one kept";
    d.why = why_not;
    return d;
  }
  d.what = "weather map inverted from the photo: the clouds where the photo has them";
  d.why = std::to_string(constrained) + " of " + std::to_string(texels) + " texels seen by the photo (the rest keep the "
          "statistics fit's coverage); rendered vs photo cloud opacity RMS";
  for (double r : rms) d.why += " " + FormatNumber(std::round(r * 1000.0) / 1000.0);
  d.why += " over " + std::to_string(rms.size()) + " renders at " + std::to_string(render_width) + " px wide";
  return d;
}

WeatherInversionRecord InvertPhotoWeather(const PhotoAnalysis& a, const StagedDirectory& out, double exposure) {
  const auto t0 = std::chrono::steady_clock::now();
  WeatherInversionRecord r;
  const render::Preset preset = render::LoadPreset(out / "preset.json");
  const int w = a.frame.radiance.width, h = a.frame.radiance.height;
  const int factor = w / kRenderWidth;
  if (preset.clouds_json.empty() || a.cloud_probability.empty() || !std::filesystem::exists(out / "preset.weather.exr")) {
    r.why_not = "no fitted clouds section, cloud probability or weather map to invert";
    return r;
  }
  if (factor < 1 || w % kRenderWidth != 0 || h % (kRenderWidth / 2) != 0) {
    r.why_not = "the photo's size " + std::to_string(w) + "x" + std::to_string(h) + " is not a multiple of " +
                std::to_string(kRenderWidth) + "x" + std::to_string(kRenderWidth / 2) + " (the refinement renders')";
    return r;
  }
  const clouds::CloudParams params = clouds::ParseCloudSectionText(preset.clouds_json, out / "preset.json");
  clouds::WeatherMap map = clouds::LoadWeatherMap(out / "preset.weather.exr", params.weather_extent_m);
  std::vector<float> photo(a.cloud_probability.size());
  for (size_t i = 0; i < photo.size(); ++i) photo[i] = a.mask.sky[i] >= 0.5f ? a.cloud_probability[i] : 0.0f;
  const int rw = kRenderWidth, rh = kRenderWidth / 2;
  const std::vector<float> photo_small = cloudfit::DownsampleLatLong(photo, w, h, rw, rh);
  const std::vector<float> sky_small = cloudfit::DownsampleLatLong(a.mask.sky, w, h, rw, rh);
  const cloudfit::WeatherTexelView view = cloudfit::ProjectWeatherTexels(params, map.width, map.height, rw, rh, sky_small);
  cloudfit::SeedCoverage(view, photo_small, SeedGain(out / "fit.json"), &map);
  GameRenderOptions ro;
  ro.preset_path = out / "preset.json";
  ro.sun_dir = *a.sun.direction;
  ro.width = rw;
  ro.height = rh;
  ro.sun_disc = false;
  ro.exposure = exposure;
  ro.verbose = false;
  ro.clouds.enabled = true;
  for (int k = 0; k < kRefinements; ++k) {
    clouds::SaveWeatherMap(map, out / "preset.weather.exr");
    const GameImage g = RenderGameImage(ro);
    r.rms.push_back(cloudfit::RefineCoverage(view, photo_small, Opacity(g.cloud_transmittance), kStep, &map));
  }
  clouds::SaveWeatherMap(map, out / "preset.weather.exr");
  r.done = true;
  r.texels = map.width * map.height;
  r.constrained = view.constrained;
  r.render_width = rw;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace skycal::controllers
