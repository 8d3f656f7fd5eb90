#include "fit_cloud_stats.h"

#include <utility>

#include "fit_report.h"
#include "render_clouds.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;

namespace {

cloudfit::PhotoCloudStatsOptions FlagValues(const FitCloudStatsOptions& o) {
  cloudfit::PhotoCloudStatsOptions p;
  p.width = o.width;
  p.maps = o.maps;
  p.renders = o.renders;
  p.max_iterations = o.max_iterations;
  p.weather_seed = o.weather_seed;
  p.sun = o.sun;
  p.probability = o.probability;
  p.sun_scale = o.sun_scale;
  p.fitted = o.fitted;
  return p;
}

nlohmann::json ErrorsJson(const fit::ImageErrors& e) {
  return {{"pixels", e.pixels}, {"rel_rmse", e.rel_rmse}, {"log_rmse", e.log_rmse}};
}

nlohmann::json SunCheckJson(const cloudfit::PhotoSunCheck& s) {
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

nlohmann::json ProbabilityJson(const cloudfit::CloudProbabilityRecord& p) {
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
nlohmann::json BinsJson(const FitCloudStatsOptions& o, const cloudfit::StatisticsFit& f, size_t r) {
  const cloudfit::CloudStatsOptions& so = f.options;
  const cloudfit::CloudStatsResult& res = f.result;
  const cloudfit::CloudStatistics& photo = res.reference_stats[r];
  const cloudfit::CloudStatistics& model = res.final_stats.empty() ? photo : res.final_stats[r];
  const int nq = static_cast<int>(so.quantiles.size());
  const int mid = nq / 2;  // the median of the default {0.25, 0.5, 0.75}
  nlohmann::json bins = nlohmann::json::array();
  for (int sb = 0; sb < photo.sun_bins; ++sb)
    for (int eb = 0; eb < photo.elevation_bins; ++eb)
      for (int k = 0; k < 2; ++k) {
        const int bin = photo.Bin(sb, eb, k);
        if (photo.weight[bin] < so.min_bin_sr) continue;
        auto medians = [&](const cloudfit::CloudStatistics& s) {
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

nlohmann::json ReferenceJson(const FitCloudStatsOptions& o, const cloudfit::PhotoCloudStatsResult& res, size_t r) {
  const cloudfit::PreparedPhoto& d = res.photos[r];
  const cloudfit::FitImage& im = res.images[r];
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

nlohmann::json SunScaleJson(const FitCloudStatsOptions& o, const cloudfit::SunScaleProfile& p) {
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
          {"scattering_albedo_held", cloudfit::kPhysicalCloudAlbedo},
          {"evaluations", p.scales.size()},
          {"time_s", p.time_s},
          {"profile", profile},
          {"why",
           std::string("the albedo of cloud water droplets is ~1 in the visible (Hansen & Travis 1974): held at ") +
               FormatNumber(cloudfit::kPhysicalCloudAlbedo) + "; the statistics then fit the clouds' direct light as a "
               "scale on the " + (o.sun == "photo" ? "photo's measured sun" : "fitted preset's sun") +
               " (the ambient fitted at each scale, the cost's minimum over the scale found by a grid over ln s and "
               "golden sections)" +
               (p.saturated ? "; the disc is saturated (sun_check), a lower bound: s >= 1" : "; s >= 0.1") +
               "; s <= the sky fit's own sun over the measured one (upper_bound)"}};
}

nlohmann::json ParametersJson(const cloudfit::StatisticsFit& f) {
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

nlohmann::json CoverageJson(const cloudfit::CoverageMatch& c) {
  nlohmann::json steps = nlohmann::json::array();
  for (const cloudfit::CoverageStep& s : c.steps)
    steps.push_back({{"mean_coverage", s.mean_coverage}, {"model_mean_opacity", s.model_mean_opacity}});
  return {{"photo_mean_cloud_probability", c.target},
          {"matched_mean_coverage", c.coverage},
          {"model_mean_opacity", c.achieved},
          {"time_s", c.time_s},
          {"steps", steps}};
}

// The statistics fit's solve: cost, renders, whitening, timing.
void AddSolveJson(const cloudfit::StatisticsFit& f, nlohmann::json* j) {
  const cloudfit::CloudStatsResult& res = f.result;
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

// fit.json's `cloud_stats` (without `preset` and `sky_refit`, which the verb adds).
nlohmann::json CloudStatsJson(const FitCloudStatsOptions& o, const cloudfit::PhotoCloudStatsResult& res) {
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

// fit/<ref>.clouds.{reference,fit,error}.png: the photo's sky, the statistical fit image.
void WriteCloudStatsPanels(const fs::path& fit_dir, const std::vector<cloudfit::CloudStatsPhoto>& photos,
                           const fit::FitResult& sky, const cloudfit::PhotoCloudStatsResult& res) {
  std::vector<fit::Reference> panel_refs;
  fit::FitResult panels = sky;
  panels.references.clear();
  for (size_t r = 0; r < res.photos.size(); ++r) {
    fit::Reference pr = res.photos[r].whole;
    pr.name = photos[r].ref->name + ".clouds";
    panel_refs.push_back(std::move(pr));
    fit::ReferenceFit rf = sky.references[r];
    rf.rendered = res.images[r].image;
    panels.references.push_back(std::move(rf));
  }
  WriteFitPanels(fit_dir.string(), panel_refs, panels);
}

// Why the preset takes the sun that lit the clouds, or keeps the sky fit's.
std::string SunWhy(const cloudfit::CloudStatsPresetUpdate& u) {
  const std::string disc = "the photo's disc " + std::string(u.disc_seen ? "seen" : "not seen") + " (peak " +
                           FormatNumber(u.weakest_peak_over_background) + "x the sky ring around it; seen from " +
                           FormatNumber(cloudfit::kVisibleDiscPeakOverSky) + "x)";
  return !u.photo_sun  ? "--cloud-stats-sun model: the clouds were lit by the sky fit's sun"
         : u.sun_fitted ? disc + "; the sun's scale fitted to the clouds (sun_scale)"
         : u.disc_seen  ? disc + ": its measured sun"
                        : disc + ": what lit the clouds is no measurement of the sun; the preset keeps "
                                 "the sky fit's, and its clouds, lit by it, render brighter than fitted";
}

}  // namespace

std::string WithCloudStatsFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"FitPhotoCloudStats:", "--clouds stats:"},
                                     {"PhotoCloudStatsOptions::width", "--cloud-stats-width"},
                                     {"PhotoCloudStatsOptions::maps", "--cloud-stats-maps"},
                                     {"PhotoCloudStatsOptions::renders", "cloud stats renders per evaluation"},
                                     {"PhotoCloudStatsOptions::max_iterations", "--cloud-stats-iterations"},
                                     {"PhotoCloudStatsOptions::sun", "--cloud-stats-sun"},
                                     {"PhotoCloudStatsOptions::probability", "--cloud-stats-probability"},
                                     {"PhotoCloudStatsOptions::sun_scale", "--cloud-stats-sun-scale"}};
  return FieldsAsFlags(message, kFlags);
}

bool FitCloudStatsOptions::IsValid(std::string* why) const {
  if (FlagValues(*this).IsValid(why)) return true;
  *why = WithCloudStatsFlags(*why);
  return false;
}

cloudfit::PhotoCloudStatsOptions PhotoCloudStatsOptionsFor(const FitCloudStatsOptions& o) {
  cloudfit::PhotoCloudStatsOptions p = FlagValues(o);
  const render::Preset cloudy = render::LoadPreset(DefaultCloudyPresetPath());
  p.initial = clouds::ParseCloudSectionText(cloudy.clouds_json, DefaultCloudyPresetPath());
  p.noise_seed = kCloudNoiseSeed;
  p.log = [](const std::string& m) { Log("fit", m); };
  return p;
}

nlohmann::json RefineCloudMaskAndRefitSky(const FitCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                          std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                          const std::function<void()>& refit) {
  cloudfit::PhotoCloudStatsOptions po = FlagValues(o);
  po.log = [](const std::string& m) { Log("fit", m); };
  const cloudfit::SkyRefit s = cloudfit::RefineCloudMaskAndRefitSky(po, user_mask, refs, probability, sky, refit);
  nlohmann::json j = {{"threshold_released_fraction", cloudfit::kSkyRefitReleasedFraction}, {"refitted", s.refitted}};
  using Skipped = cloudfit::SkyRefit::Skipped;
  if (s.skipped == Skipped::kInitialProbability) {
    j["why"] = "--cloud-stats-probability initial: the first mask stays";
    return j;
  }
  if (s.skipped == Skipped::kUserMask) {
    j["why"] = "a --mask is given: its pixels and the cloud mask's are both user-masked, none released";
    return j;
  }
  nlohmann::json per_ref = nlohmann::json::array();
  for (const cloudfit::ReleasedPixels& r : s.references) {
    nlohmann::json rj = {{"name", r.name}, {"sky_fit_clear_rel_rmse", r.sky_fit_clear_rel_rmse}};
    if (!r.refined) {
      rj["released_pixels"] = 0;
      rj["why"] = "the sky fit misses its clear pixels by more than 50%: no clear-sky expectation";
    } else {
      rj["sun_angle_edges_deg"] = r.sun_angle_edges_deg;
      rj["initial_cloud_pixels_by_sun_angle"] = r.initial_cloud_pixels_by_sun_angle;
      rj["cloud_pixels_by_sun_angle"] = r.cloud_pixels_by_sun_angle;
      rj["released_pixels"] = r.released;
      rj["released_fraction"] = r.released_fraction;
    }
    per_ref.push_back(rj);
  }
  j["references"] = per_ref;
  if (s.skipped == Skipped::kBelowThreshold) {
    j["why"] = "no reference's mask changed by more than the threshold";
    return j;
  }
  j["time_s"] = s.time_s;
  j["why"] = "the cloud mask against the sky fit's own render released more than the threshold of a reference's sky "
             "pixels: the atmosphere fitted once more on them (from the first fit's preset)";
  return j;
}

nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<cloudfit::CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const fs::path& fit_dir,
                                     cloudfit::CloudStatsPresetUpdate* update) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const cloudfit::PhotoCloudStatsOptions po = PhotoCloudStatsOptionsFor(o);
  cloudfit::PhotoCloudStatsResult result;
  try {
    result = cloudfit::FitPhotoCloudStats(po, photos, sky);
  } catch (const Error& e) {
    throw Error(WithCloudStatsFlags(e.what()));
  }
  WriteCloudStatsPanels(fit_dir, photos, sky, result);
  if (update) *update = result.update;
  return CloudStatsJson(o, result);
}

nlohmann::json AttachCloudStats(const cloudfit::CloudStatsPresetUpdate& update, const fs::path& preset_json,
                                render::Preset* preset) {
  clouds::CloudParams p = update.params;
  const std::string weather_name = preset_json.stem().string() + ".weather.exr";
  clouds::SaveWeatherMap(update.weather, (preset_json.parent_path() / weather_name).string());
  p.weather_map = weather_name;
  preset->clouds_json = clouds::CloudSectionToJson(p).dump();
  const std::string why = SunWhy(update);
  const nlohmann::json record = {
      {"clouds_section", "the fitted cloud lighting; weather_map " + weather_name +
                             ": noise at the matched mean coverage (the photo's shapes are unknown, its cover is not)"},
      {"weather_map", weather_name},
      {"sun_illuminance_lux", {{"sky_fit", preset->sun_illuminance_lux}, {"clouds_lit_by", update.sun_illuminance_lux}}},
      {"sun_tint_rgb", {{"sky_fit", preset->sun_tint_rgb}, {"clouds_lit_by", update.sun_tint_rgb}}},
      {"sun_written", update.sun_measured ? "clouds_lit_by" : "sky_fit"},
      {"why", why + (update.sun_measured ? std::string(": the preset takes it, so it renders what was fitted "
                                                       "(the sky's radiance does not depend on the sun's "
                                                       "illuminance; the disc, the ground and the clouds do)")
                                         : std::string())}};
  if (update.sun_measured) {
    preset->sun_illuminance_lux = update.sun_illuminance_lux;
    preset->sun_tint_rgb = update.sun_tint_rgb;
  }
  return record;
}

}  // namespace skycal::cli
