// Stage 4 of FitPhotoCloudStats: the statistics fit, and with the albedo held physical the
// profile of its cost over a scale on the sun that lights the clouds.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "photo_cloud_stats_stages.h"
#include "skycal/cloudfit/cloud_sun_scale.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"

namespace skycal::cloudfit {
namespace {

// The profile over s: at each s the ambient fitted from the best ambient so far. The disc
// bounds s from below where every photo's disc is a lower bound (saturated). Leaves the best
// fit in `best` and the basis at the found scale.
SunScaleProfile ProfileSunScale(const PhotoCloudStatsOptions& o, const std::vector<PreparedPhoto>& photos,
                                const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                                const CloudStatsOptions& so, LightingBasisCloudRenderer& basis,
                                const render::Preset& sky_preset, double measured_lux, CloudStatsResult* best) {
  SunScaleProfile p;
  p.saturated = o.sun == "photo" &&
                std::all_of(photos.begin(), photos.end(), [](const PreparedPhoto& d) { return d.sun_check.saturated; });
  SunScaleSearchOptions ss;
  ss.lower = p.saturated ? 1.0 : 0.1;
  ss.upper = std::min(sky_preset.sun_illuminance_lux, 2.0e5) / measured_lux;
  if (!(ss.upper > ss.lower)) ss.upper = ss.lower * 1.5;
  const auto t0 = std::chrono::steady_clock::now();
  double best_cost = INFINITY;
  const SunScaleSearch found = MinimizeOverSunScale(
      [&](double sc) {
        basis.set_sun_scale(sc);
        CloudStatsScene at = scene;
        if (best_cost < INFINITY) at.initial.ambient_strength = best->params.ambient_strength;
        CloudStatsResult r = FitCloudStats(refs, at, basis, so);
        p.iterations.push_back(r.iterations);
        LogStage(o, "clouds stats: sun scale " + FormatNumber(sc) + ": ambient " + FormatNumber(r.params.ambient_strength) +
                        ", cost " + FormatNumber(r.final_cost) + " (" + std::to_string(r.iterations) + " iterations)");
        const double cost = r.final_cost;
        if (cost < best_cost) {
          best_cost = cost;
          *best = std::move(r);
        }
        return cost;
      },
      ss);
  p.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  basis.set_sun_scale(found.scale);
  best->time_s = p.time_s;
  p.measured_lux = measured_lux;
  p.scale = found.scale;
  p.fitted_lux = measured_lux * found.scale;
  p.lower = ss.lower;
  p.upper = ss.upper;
  p.at_lower = found.at_lower;
  p.at_upper = found.at_upper;
  p.scales = found.scales;
  p.costs = found.costs;
  for (const PreparedPhoto& d : photos) p.sky_fit_sun_lux_green.push_back(d.sun_check.model_lux[1]);
  LogStage(o, "clouds stats: the clouds' sun " + FormatNumber(found.scale) + " x the measured " + FormatNumber(measured_lux) +
                  " lux = " + FormatNumber(p.fitted_lux) + " lux (" + std::to_string(found.scales.size()) +
                  " statistics fits, " + FormatNumber(p.time_s) + " s)");
  return p;
}

}  // namespace

StatisticsFit FitStatistics(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so_in,
                            const std::vector<PreparedPhoto>& photos, const CoverageMatch& coverage,
                            const clouds::CloudNoise& noise, clouds::CloudRenderer& renderer,
                            const render::Preset& sky_preset, render::Preset* cloud_preset) {
  StatisticsFit out;
  CloudStatsOptions& so = out.options;
  so = so_in;
  std::vector<CloudStatsReference> refs;
  for (const PreparedPhoto& d : photos) refs.push_back(d.stats_ref);
  CloudStatsScene scene{cloud_preset, o.initial, &noise, &coverage.maps[0]};
  for (const auto& m : coverage.maps) scene.weather_ensemble.push_back(&m);
  out.fit_sun = o.sun_scale == "fit";
  if (out.fit_sun) {  // the albedo held physical; the sun's scale takes its place (below)
    so.fitted.erase(std::remove(so.fitted.begin(), so.fitted.end(), "scattering_albedo"), so.fitted.end());
    scene.initial.scattering_albedo = kPhysicalCloudAlbedo;
  }
  LogStage(o, "clouds stats: fitting " + std::to_string(so.fitted.size()) + " lighting parameters" +
                  (out.fit_sun ? " and the sun's scale" : "") + " (" + std::to_string(o.renders) + " renders of " +
                  std::to_string(o.maps) + " weather maps per evaluation, " + std::to_string(o.width) + "x" +
                  std::to_string(o.width / 2) + ", at most " + std::to_string(o.max_iterations) + " iterations)");
  // When only the linear lighting (albedo, ambient) is fitted, each draw of shapes is
  // marched three times (four with a sun scale) and every evaluation after that is a weighted
  // sum of those (lighting_basis_renderer.h); otherwise every evaluation marches.
  out.linear = std::all_of(so.fitted.begin(), so.fitted.end(), [](const std::string& n) {
    return n == "scattering_albedo" || n == "ambient_strength";
  });
  if (out.fit_sun && !out.linear)
    throw Error("PhotoCloudStatsOptions::sun_scale = 'fit' needs the linear lighting alone in "
                "PhotoCloudStatsOptions::fitted (scattering_albedo, ambient_strength)");
  LightingBasisCloudRenderer basis(renderer, static_cast<int>(refs.size()) * o.renders + 1);
  clouds::CloudRenderer& fit_renderer = out.linear ? static_cast<clouds::CloudRenderer&>(basis) : renderer;
  if (!out.fit_sun) {
    out.result = FitCloudStats(refs, scene, fit_renderer, so);
  } else {
    out.sun_scale = ProfileSunScale(o, photos, refs, scene, so, basis, sky_preset, cloud_preset->sun_illuminance_lux,
                                    &out.result);
    cloud_preset->sun_illuminance_lux = out.sun_scale.fitted_lux;
  }
  const CloudStatsResult& res = out.result;
  out.marches = out.linear ? basis.marches() : res.renders;
  out.renderer = fit_renderer.Describe();
  LogStage(o, "clouds stats: cost " + FormatNumber(res.initial_cost) + " -> " + FormatNumber(res.final_cost) + ", " +
                  std::to_string(res.renders) + " evaluations' renders (" + std::to_string(out.marches) + " marched), " +
                  FormatNumber(res.time_s) + " s");
  return out;
}

}  // namespace skycal::cloudfit
