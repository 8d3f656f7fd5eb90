// FitPhotoCloudStats: the stages of photo_cloud_stats.h in sequence; the sun that lights the
// model's clouds (stage 2) and what the fitted preset takes (stage 6).
#include "skycal/cloudfit/photo_cloud_stats.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "photo_cloud_stats_stages.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"

namespace skycal::cloudfit {

bool PhotoCloudStatsOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& field, const std::string& value, const std::string& expected) {
    *why = "PhotoCloudStatsOptions::" + field + " = " + value + " (expected " + expected + ")";
    return false;
  };
  if (width < 16 || width > 1024 || width % 2 != 0)
    return bad("width", std::to_string(width), "an even number of pixels in [16, 1024]");
  if (maps < 1 || maps > 16) return bad("maps", std::to_string(maps), "an integer in [1, 16]");
  if (renders < maps || renders > 64) return bad("renders", std::to_string(renders), "[maps, 64]");
  if (sun != "photo" && sun != "model") return bad("sun", "'" + sun + "'", "photo or model");
  if (probability != "fitted" && probability != "initial")
    return bad("probability", "'" + probability + "'", "fitted or initial");
  if (sun_scale != "fit" && sun_scale != "off") return bad("sun_scale", "'" + sun_scale + "'", "fit or off");
  if (max_iterations < 0 || max_iterations > 200)
    return bad("max_iterations", std::to_string(max_iterations), "an integer in [0, 200]");
  return true;
}

void LogStage(const PhotoCloudStatsOptions& o, const std::string& message) {
  if (o.log) o.log(message);
}

CloudStatsOptions StatsOptionsFor(const PhotoCloudStatsOptions& o) {
  CloudStatsOptions so;
  so.render_width = o.width;
  so.render_height = o.width / 2;
  so.model_renders = o.renders;
  so.max_iterations = o.max_iterations;
  so.fitted = o.fitted;
  // A bin the photo fills and the render empties costs as much as a 2-log-unit (7x) miss
  // of each quantile: more than any bin's start is off on the three photos.
  so.empty_bin_log_residual = 2.0;
  return so;
}

render::Preset CloudSunPreset(const PhotoCloudStatsOptions& o, const std::vector<PreparedPhoto>& photos,
                              const render::Preset& sky_preset) {
  render::Preset cloud_preset = sky_preset;
  if (o.sun != "photo") return cloud_preset;
  std::array<double, 3> log_ratio{};
  for (const PreparedPhoto& d : photos)
    for (int c = 0; c < 3; ++c) log_ratio[c] += std::log(std::max(d.sun_check.photo_over_model[c], 1e-6)) / photos.size();
  const double g = std::exp(log_ratio[1]);
  cloud_preset.sun_illuminance_lux = std::clamp(sky_preset.sun_illuminance_lux * g, 1.0, 2.0e5);
  for (int c = 0; c < 3; ++c)
    cloud_preset.sun_tint_rgb[c] = std::clamp(sky_preset.sun_tint_rgb[c] * std::exp(log_ratio[c]) / g, 0.0, 10.0);
  LogStage(o, "clouds stats: the clouds lit by the photo's sun: " + FormatNumber(cloud_preset.sun_illuminance_lux) +
                  " lux (the fitted preset's " + FormatNumber(sky_preset.sun_illuminance_lux) + ")");
  return cloud_preset;
}

CloudStatsPresetUpdate PresetUpdateFor(const PhotoCloudStatsOptions& o, const std::vector<PreparedPhoto>& photos,
                                       const StatisticsFit& fit, const render::Preset& cloud_preset,
                                       const clouds::WeatherMap& weather) {
  CloudStatsPresetUpdate u;
  u.params = fit.result.params;
  u.weather = weather;
  u.sun_illuminance_lux = cloud_preset.sun_illuminance_lux;
  u.sun_tint_rgb = cloud_preset.sun_tint_rgb;
  double weakest = INFINITY;
  for (const PreparedPhoto& d : photos) weakest = std::min(weakest, d.sun_check.peak_over_background);
  u.weakest_peak_over_background = weakest;
  u.disc_seen = weakest >= kVisibleDiscPeakOverSky;
  // The preset takes the sun that lit the clouds when it is a measurement (the disc seen)
  // or a fit (sun_scale "fit": the clouds' brightness sets it, within bounds from the disc):
  // either way it is the sun this fit stands for.
  u.photo_sun = o.sun == "photo";
  u.sun_fitted = fit.fit_sun;
  u.sun_measured = u.photo_sun && (u.disc_seen || u.sun_fitted);
  return u;
}

namespace {

// Vulkan (the game's path) when a device is there, else the float CPU march.
std::unique_ptr<clouds::CloudRenderer> CreateStatsRenderer(const PhotoCloudStatsOptions& o) {
  try {
    return clouds::CreateVulkanCloudRenderer(false);
  } catch (const Error& e) {
    LogStage(o, std::string("clouds stats: no Vulkan device (") + e.what() + "): the float CPU march renders");
    return clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2);
  }
}

}  // namespace

PhotoCloudStatsResult FitPhotoCloudStats(const PhotoCloudStatsOptions& o, const std::vector<CloudStatsPhoto>& photos,
                                         const fit::FitResult& sky) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const CloudStatsOptions so = StatsOptionsFor(o);
  PhotoCloudStatsResult out;
  auto sky_renderer = render::CreateRenderer(render::Backend::kCpu);
  for (size_t r = 0; r < photos.size(); ++r)
    out.photos.push_back(PreparePhoto(o, so, photos[r], sky.references[r], sky.preset, *sky_renderer));
  out.cloud_preset = CloudSunPreset(o, out.photos, sky.preset);
  const std::unique_ptr<clouds::CloudRenderer> renderer = CreateStatsRenderer(o);
  const auto noise = clouds::SharedCloudNoise(
      o.noise_seed, o.noise_cache_dir.empty() ? clouds::UsableCloudNoiseCacheDir() : o.noise_cache_dir);
  out.coverage = MatchCoverage(o, so, out.photos, out.cloud_preset, *noise, *renderer);
  out.fit = FitStatistics(o, so, out.photos, out.coverage, *noise, *renderer, sky.preset, &out.cloud_preset);
  const CloudStatsResult& res = out.fit.result;
  for (size_t r = 0; r < photos.size(); ++r) {
    const CloudStatistics& model = res.final_stats.empty() ? res.reference_stats[r] : res.final_stats[r];
    out.images.push_back(SynthesizeFitImage(out.fit.options, out.photos[r], *photos[r].ref, sky.references[r], model));
  }
  out.update = PresetUpdateFor(o, out.photos, out.fit, out.cloud_preset, out.coverage.maps[0]);
  return out;
}

}  // namespace skycal::cloudfit
