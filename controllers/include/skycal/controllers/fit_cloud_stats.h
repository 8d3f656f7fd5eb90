// The fit controller's cloud statistics stage (`skycal fit --clouds stats`): the cloud lighting
// of photographs, whose cloud shapes no noise reproduces (docs/cloud-fitting.md, regime 3): the
// options, their check, the call of cloudfit::FitPhotoCloudStats
// (skycal/cloudfit/photo_cloud_stats.h: the stages and what each means), fit.json's
// `cloud_stats` object (its fields: skycal/cloudfit/photo_cloud_stats_json.h) and the panels
// fit/<ref>.clouds.{reference,fit,error}.png. Errors name PhotoCloudStatsOptions' fields.
#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/cloudfit/photo_cloud_stats.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {

// cloudfit::PhotoCloudStatsOptions's fields of the same names (which say why), and whether
// the stage runs.
struct FitCloudStatsOptions {
  bool enabled = false;        // the stage runs (it needs FitControllerOptions::cloud_mask)
  int width = 128;
  int maps = 4;
  int renders = 8;             // 2 x maps
  int max_iterations = 12;
  uint64_t weather_seed = 1;
  std::string sun = "photo";           // photo|model
  std::string probability = "fitted";  // fitted|initial
  std::string sun_scale = "fit";       // fit|off
  std::vector<std::string> fitted = cloudfit::PhotoCloudStatsOptions{}.fitted;
  // The library's check: false and PhotoCloudStatsOptions::<field>, its value and the
  // expectation in *why.
  bool IsValid(std::string* why) const;
};

// The library's options for `o`: the start from the bundled default_cloudy preset, the noise
// every render uses, progress on stderr ([fit]).
cloudfit::PhotoCloudStatsOptions PhotoCloudStatsOptionsFor(const FitCloudStatsOptions& o);

// cloudfit::RefineCloudMaskAndRefitSky as fit.json's `cloud_stats.sky_refit`.
nlohmann::json RefineCloudMaskAndRefitSky(const FitCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                          std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                          const std::function<void()>& refit);

// Runs the statistics fit over `photos` (one lighting for all of them) with the sky fit's
// preset and exposures; writes the panels into `fit_dir` (empty: none, and the record names
// no image); returns fit.json's `cloud_stats`
// and, when `update` is given, what the fitted preset takes from it. Throws skycal::Error
// naming the reference when its size is not a multiple of PhotoCloudStatsOptions::width or it
// has no cloud to fit.
nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<cloudfit::CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const std::filesystem::path& fit_dir,
                                     cloudfit::CloudStatsPresetUpdate* update = nullptr);

// Writes the statistics fit into the fitted preset: its `clouds` section (the fitted lighting,
// weather_map naming <stem>.weather.exr written beside preset.json) and the sun that lit the
// clouds (illuminance and tint) when update.sun_measured. Returns fit.json's
// `cloud_stats.preset` record: what changed, from what to what, and why.
nlohmann::json AttachCloudStats(const cloudfit::CloudStatsPresetUpdate& update, const std::filesystem::path& preset_json,
                                render::Preset* preset);

}  // namespace skycal::controllers
