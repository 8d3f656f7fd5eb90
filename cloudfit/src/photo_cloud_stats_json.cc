#include "skycal/cloudfit/photo_cloud_stats_json.h"

#include <string>

#include "skycal/core/format_number.h"

namespace skycal::cloudfit {
namespace {

nlohmann::json ErrorsJson(const fit::ImageErrors& e) {
  return {{"pixels", e.pixels}, {"rel_rmse", e.rel_rmse}, {"log_rmse", e.log_rmse}};
}

nlohmann::json SunCheckJson(const PhotoSunCheck& s) {
  return {{"photo_lux_model_units", s.photo_lux_model_units},
          {"model_lux", s.model_lux},
          {"photo_over_model", s.photo_over_model},
          {"disc_pixels", s.disc_pixels},
          {"peak_over_background", s.peak_over_background},
          {"clipped", s.clipped},
          {"direct_to_diffuse", s.direct_to_diffuse},
          {"clean_disc", s.clean_disc},
          {"saturated", s.saturated},
          {"note", "the photo's disc + blur within 3 deg above the median of a 4-6 deg ring, divided by the exposure; "
                   "clipped: more than 2 disc pixels within 0.1% of the peak at the frame's own resolution; "
                   "direct_to_diffuse: the disc's light on a horizontal surface over the sky's outside it (green); "
                   "saturated (the disc a lower bound): clipped, or a clean disc (peak >= 100x its ring) with "
                   "direct_to_diffuse < 0.5, which an unveiled sun does not give"}};
}

nlohmann::json ProbabilityJson(const CloudProbabilityRecord& p) {
  nlohmann::json j = {{"expectation", p.expectation},
                      {"sun_angle_edges_deg", p.sun_angle_edges_deg},
                      {"initial_cloud_pixels_by_sun_angle", p.initial_cloud_pixels_by_sun_angle},
                      {"sky_fit_clear_rel_rmse", p.sky_fit_clear_rel_rmse},
                      {"refined", p.refined}};
  if (p.refined_before) j["refined_against"] = "the first sky fit (before the sky refit: sky_refit)";
  if (!p.cloud_pixels_by_sun_angle.empty()) j["cloud_pixels_by_sun_angle"] = p.cloud_pixels_by_sun_angle;
  return j;
}

// Per bin the photo fills: its solid angle and the log-median radiance of the photo, the
// fitted model and the start.
nlohmann::json BinsJson(const PhotoCloudStatsOptions& o, const StatisticsFit& f, size_t r) {
  const CloudStatsOptions& so = f.options;
  const CloudStatsResult& res = f.result;
  const CloudStatistics& photo = res.reference_stats[r];
  const CloudStatistics& model = res.final_stats.empty() ? photo : res.final_stats[r];
  const int nq = static_cast<int>(so.quantiles.size());
  const int mid = nq / 2;  // the median of the default {0.25, 0.5, 0.75}
  nlohmann::json bins = nlohmann::json::array();
  for (int sb = 0; sb < photo.sun_bins; ++sb)
    for (int eb = 0; eb < photo.elevation_bins; ++eb)
      for (int k = 0; k < 2; ++k) {
        const int bin = photo.Bin(sb, eb, k);
        if (photo.weight[bin] < so.min_bin_sr) continue;
        auto medians = [&](const CloudStatistics& s) {
          nlohmann::json m = nlohmann::json::array();
          for (int ch = 0; ch < 3; ++ch) m.push_back(s.log_quantile[(static_cast<size_t>(bin) * 3 + ch) * nq + mid]);
          return m;
        };
        bins.push_back({{"sun_angle_deg", {so.sun_angle_edges_deg[sb], so.sun_angle_edges_deg[sb + 1]}},
                        {"elevation_deg", {so.elevation_edges_deg[eb], so.elevation_edges_deg[eb + 1]}},
                        {"opacity_class", k == 0 ? "thin" : "thick"},
                        {"photo_sr", photo.weight[bin]},
                        {"model_sr", model.weight[bin] / o.renders},
                        {"photo_log_median_rgb", medians(photo)},
                        {"fit_log_median_rgb", medians(model)},
                        {"initial_log_median_rgb", res.initial_stats.empty() ? nlohmann::json() : medians(res.initial_stats[r])}});
      }
  return bins;
}

nlohmann::json ReferenceJson(const PhotoCloudStatsOptions& o, const PhotoCloudStatsResult& res, size_t r) {
  const PreparedPhoto& d = res.photos[r];
  const FitImage& im = res.images[r];
  const std::string& name = d.stats_ref.name;
  const nlohmann::json errors = {
      {"atmosphere_only", {{"whole_sky", ErrorsJson(im.atmosphere_whole)},
                           {"clear", ErrorsJson(im.atmosphere_clear)},
                           {"cloud", ErrorsJson(im.atmosphere_cloud)}}},
      {"with_cloud_statistics", {{"whole_sky", ErrorsJson(im.stats_whole)},
                                 {"clear", ErrorsJson(im.stats_clear)},
                                 {"cloud", ErrorsJson(im.stats_cloud)}}}};
  return {{"name", name},
          {"non_sky_pixels_segmented", d.non_sky_segmented},
          {"sun_check", SunCheckJson(d.sun_check)},
          {"cloud_probability", ProbabilityJson(d.probability_record)},
          {"photo_mean_cloud_probability", d.mean_cloud_probability},
          {"errors", errors},
          {"bins", BinsJson(o, res.fit, r)},
          {"images", {{"reference", "fit/" + name + ".clouds.reference.png"},
                      {"fit", "fit/" + name + ".clouds.fit.png"},
                      {"error", "fit/" + name + ".clouds.error.png"}}}};
}

nlohmann::json SunScaleJson(const PhotoCloudStatsOptions& o, const SunScaleProfile& p) {
  nlohmann::json profile = nlohmann::json::array();
  for (size_t i = 0; i < p.scales.size(); ++i)
    profile.push_back({{"scale", p.scales[i]}, {"cost", p.costs[i]}, {"iterations", p.iterations[i]}});
  return {{"measured_lux", p.measured_lux},
          {"scale", p.scale},
          {"fitted_lux", p.fitted_lux},
          {"sky_fit_sun_lux_green", p.sky_fit_sun_lux_green},
          {"lower_bound", p.lower},
          {"upper_bound", p.upper},
          {"at_lower_bound", p.at_lower},
          {"at_upper_bound", p.at_upper},
          {"scattering_albedo_held", kPhysicalCloudAlbedo},
          {"evaluations", p.scales.size()},
          {"time_s", p.time_s},
          {"profile", profile},
          {"why",
           std::string("the albedo of cloud water droplets is ~1 in the visible (Hansen & Travis 1974): held at ") +
               FormatNumber(kPhysicalCloudAlbedo) + "; the statistics then fit the clouds' direct light as a "
               "scale on the " + (o.sun == "photo" ? "photo's measured sun" : "fitted preset's sun") +
               " (the ambient fitted at each scale, the cost's minimum over the scale found by a grid over ln s and "
               "golden sections)" +
               (p.saturated ? "; the disc is saturated (sun_check), a lower bound: s >= 1" : "; s >= 0.1") +
               "; s <= the sky fit's own sun over the measured one (upper_bound)"}};
}

nlohmann::json ParametersJson(const StatisticsFit& f) {
  nlohmann::json params = nlohmann::json::object();
  for (const auto& p : f.result.parameters) {
    params[p.name] = {{"value", p.value}, {"unit", p.unit}, {"initial", p.initial}, {"held", p.held}};
    if (p.held) params[p.name]["why"] = p.why_held;
  }
  if (f.fit_sun)
    params["scattering_albedo"]["why"] = "water droplets' physical single-scattering albedo in the visible (Hansen & Travis 1974); "
                                         "the sun's scale is fitted instead (sun_scale)";
  return params;
}

nlohmann::json CoverageJson(const CoverageMatch& c) {
  nlohmann::json steps = nlohmann::json::array();
  for (const CoverageStep& s : c.steps)
    steps.push_back({{"mean_coverage", s.mean_coverage}, {"model_mean_opacity", s.model_mean_opacity}});
  return {{"photo_mean_cloud_probability", c.target},
          {"matched_mean_coverage", c.coverage},
          {"model_mean_opacity", c.achieved},
          {"time_s", c.time_s},
          {"steps", steps}};
}

// The statistics fit's solve: cost, renders, whitening, timing.
void AddSolveJson(const StatisticsFit& f, nlohmann::json* j) {
  const CloudStatsResult& res = f.result;
  (*j)["initial_cost"] = res.initial_cost;
  (*j)["final_cost"] = res.final_cost;
  (*j)["iterations"] = res.iterations;
  (*j)["renders"] = res.renders;
  (*j)["marched_renders"] = f.marches;
  (*j)["renderer"] = f.renderer;
  (*j)["singular_values"] = res.singular_values;
  (*j)["whitening"] = {{"covariance", res.noise_covariance},
                       {"draws", res.noise_draws},
                       {"shrinkage", res.noise_shrinkage},
                       {"median_noise_sd", res.median_noise_sd}};
  (*j)["termination"] = res.termination;
  (*j)["time_s"] = res.time_s;
}

}  // namespace

nlohmann::json PhotoCloudStatsJson(const PhotoCloudStatsOptions& o, const PhotoCloudStatsResult& res) {
  const render::Preset& lit = res.cloud_preset;
  nlohmann::json per_ref = nlohmann::json::array();
  for (size_t r = 0; r < res.photos.size(); ++r) per_ref.push_back(ReferenceJson(o, res, r));
  nlohmann::json j = {
      {"term", "cloud statistics (unknown shapes): weighted quantiles of log radiance per (sun angle x elevation x "
               "opacity) bin, model pooled over an ensemble of weather maps"},
      {"shared_with_atmosphere", o.sun == "photo"
                                     ? "the sky's SH-9 ambient and the sun's transmittance come from the fitted preset; "
                                       "the sun's illuminance and tint from the photo's disc (sun_check)"
                                     : "the sun's illuminance, tint and transmittance and the sky's SH-9 ambient come "
                                       "from the fitted preset"},
      {"sun", o.sun},
      {"cloud_sun_illuminance_lux", lit.sun_illuminance_lux},
      {"cloud_sun_tint_rgb", lit.sun_tint_rgb},
      {"direct_light_lux_at_albedo_1", res.fit.result.params.scattering_albedo * lit.sun_illuminance_lux},
      {"sun_scale", res.fit.fit_sun ? SunScaleJson(o, res.fit.sun_scale) : nlohmann::json(nullptr)},
      {"render_size", {o.width, o.width / 2}},
      {"weather_maps", o.maps},
      {"renders_per_evaluation", o.renders},
      {"coverage", CoverageJson(res.coverage)},
      {"parameters", ParametersJson(res.fit)},
      {"notes", {{"fit image", "clear pixels: the atmosphere's fit; cloud pixels: by their cloud membership, the "
                               "fitted model's median radiance of their bin (the photo's cloud map places them)"},
                 {"model_sr", "per render (the pooled weight divided by the renders)"}}},
      {"references", per_ref}};
  AddSolveJson(res.fit, &j);
  return j;
}

}  // namespace skycal::cloudfit
