#include "skycal/controllers/fit_cloud_stats.h"

#include <utility>

#include "fit_report.h"
#include "skycal/cloudfit/photo_cloud_stats_json.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "fit_internal.h"

namespace skycal::controllers {
namespace fs = std::filesystem;

namespace {

cloudfit::PhotoCloudStatsOptions LibraryOptions(const FitCloudStatsOptions& o) {
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

bool FitCloudStatsOptions::IsValid(std::string* why) const { return LibraryOptions(*this).IsValid(why); }

cloudfit::PhotoCloudStatsOptions PhotoCloudStatsOptionsFor(const FitCloudStatsOptions& o) {
  cloudfit::PhotoCloudStatsOptions p = LibraryOptions(o);
  const render::Preset cloudy = render::LoadPreset(DefaultCloudyPresetPath());
  p.initial = clouds::ParseCloudSectionText(cloudy.clouds_json, DefaultCloudyPresetPath());
  p.noise_seed = kRenderCloudNoiseSeed;
  p.log = [](const std::string& m) { FitLog(m); };
  return p;
}

nlohmann::json RefineCloudMaskAndRefitSky(const FitCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                          std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                          const std::function<void()>& refit) {
  cloudfit::PhotoCloudStatsOptions po = LibraryOptions(o);
  po.log = [](const std::string& m) { FitLog(m); };
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
  const cloudfit::PhotoCloudStatsResult result = cloudfit::FitPhotoCloudStats(po, photos, sky);
  if (!fit_dir.empty()) WriteCloudStatsPanels(fit_dir, photos, sky, result);
  if (update) *update = result.update;
  nlohmann::json j = cloudfit::PhotoCloudStatsJson(po, result);
  if (fit_dir.empty())
    for (nlohmann::json& r : j["references"]) r.erase("images");
  return j;
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

}  // namespace skycal::controllers
