// Stage 3 of FitPhotoCloudStats: the weather maps' mean coverage matched to the photos' cloud.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "photo_cloud_stats_stages.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/format_number.h"

namespace skycal::cloudfit {
namespace {

clouds::WeatherMap StatsWeather(uint64_t seed, double extent_m, double mean_coverage) {
  clouds::WeatherNoiseOptions w;  // default_cloudy's statistics of shapes, the coverage matched
  w.mean_coverage = mean_coverage;
  w.coverage_contrast = 3.0;
  w.coverage_cells = 8;
  return clouds::NoiseWeatherMap(seed, 256, extent_m, w);
}

// The model's mean opacity at `coverage`, pooled over the ensemble of o.maps weather maps
// (made here into `maps`) and the photos, at the starting lighting.
double ModelOpacity(const PhotoCloudStatsOptions& o, const CloudStatsOptions& opacity_only,
                    const std::vector<PreparedPhoto>& photos, const render::Preset& cloud_preset,
                    const clouds::CloudNoise& noise, clouds::CloudRenderer& renderer, double coverage,
                    std::vector<clouds::WeatherMap>* maps) {
  const double min_el = opacity_only.elevation_edges_deg.front();
  maps->clear();
  for (int m = 0; m < o.maps; ++m) maps->push_back(StatsWeather(o.weather_seed + m, o.initial.weather_extent_m, coverage));
  CloudStatsScene scene{&cloud_preset, o.initial, &noise, &(*maps)[0]};
  double mean = 0.0;
  for (const PreparedPhoto& d : photos)
    for (int m = 0; m < o.maps; ++m)
      mean += MeanOpacity(RenderForCloudStats(d.stats_ref, scene, o.initial, renderer, opacity_only, 0.0, &(*maps)[m]).opacity,
                          d.stats_ref.sky, o.width, o.width / 2, min_el) /
              (photos.size() * o.maps);
  return mean;
}

}  // namespace

// Coverage first: match the weather maps' mean coverage until the model's mean opacity
// (pooled over the ensemble, at the starting lighting) equals the photos' mean cloud
// probability over their sky above the lowest elevation bin.
CoverageMatch MatchCoverage(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so,
                            const std::vector<PreparedPhoto>& photos, const render::Preset& cloud_preset,
                            const clouds::CloudNoise& noise, clouds::CloudRenderer& renderer) {
  // Opacity only: the transmittance depends on the extinction and the shapes, never on the
  // light samples (cloud_march.glsl.h: the light march feeds the source term alone), so the
  // match marches without them.
  CloudStatsOptions opacity_only = so;
  opacity_only.march.light_samples = 0;
  CoverageMatch out;
  for (const PreparedPhoto& d : photos) out.target += d.mean_cloud_probability / photos.size();
  const double target = out.target;
  const auto t0 = std::chrono::steady_clock::now();
  // The Illinois variant of regula falsi on f(c) = opacity(c) - photo: the opacity rises
  // monotonically with the coverage from 0 (no cloud) toward 1, the anchors' assumed values
  // until evaluated points replace them; it stops within 0.005 of the photo (3-4 steps on
  // the real skies, where 8 halvings took 8) or after 8 steps.
  double lo = 0.0, hi = 1.0, f_lo = -target, f_hi = 1.0 - target;
  int side = 0;
  for (int step = 0; step < 8; ++step) {
    out.coverage = std::clamp((lo * f_hi - hi * f_lo) / (f_hi - f_lo), 1e-3, 1.0);
    out.achieved = ModelOpacity(o, opacity_only, photos, cloud_preset, noise, renderer, out.coverage, &out.maps);
    out.steps.push_back({out.coverage, out.achieved});
    LogStage(o, "clouds stats: coverage " + FormatNumber(out.coverage) + " -> model mean opacity " +
                    FormatNumber(out.achieved) + " (photo " + FormatNumber(target) + ")");
    const double f = out.achieved - target;
    if (std::abs(f) < 0.005) break;
    if (f < 0.0) {
      lo = out.coverage;
      f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = out.coverage;
      f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace skycal::cloudfit
