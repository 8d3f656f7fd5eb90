// The clouds part of `skycal fit` (docs/cloud-fitting.md): --clouds auto|on|off, the known shapes
// (--cloud-preset, --cloud-time), the decision, the joint fit through
// cloudfit::FitSkyAndClouds, and fit.json's `clouds` object. Kept apart from fit_verb.cc
// so the sky-only verb reads as before.
#pragma once
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/cloudfit/cloud_lighting_fit.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/core/file_safety.h"

namespace skycal::cli {

struct FitCloudOptions {
  std::string mode = "auto";        // --clouds auto|on|off
  std::string preset;               // --cloud-preset PRESET.json: a clouds section (shapes + start lighting)
  // --cloud-time S: the wind time of every reference; unset: each reference's
  // skycalCloudTimeS attribute (render --clouds --cloud-time writes it), else 0
  std::optional<double> time_s;
  double day_smoothness = 0.02;     // --cloud-day-smoothness L: the day's prior over time of day
  int samples = 256;                // --cloud-samples N: cloud pixels in the Jacobian
  std::vector<std::string> hold;    // --cloud-hold NAME (repeatable)
  bool IsValid(std::string* why) const;
};

// Files the clouds part reads (the cloud preset and its weather map) for file_safety.h.
std::vector<NamedPath> FitCloudInputs(const FitCloudOptions& o);

// The known shapes of --cloud-preset, loaded (noise from its seed cache); null without one.
struct LoadedCloudShapes {
  std::string origin, weather_origin;
  clouds::CloudNoise noise;
  clouds::WeatherMap weather;
  cloudfit::KnownCloudShapes shapes;  // points into noise and weather (do not copy)
};
std::unique_ptr<LoadedCloudShapes> LoadFitCloudShapes(const FitCloudOptions& o);

// Runs the fit with or without clouds (the decision first: a bad --clouds on fails before
// any solve). Each reference's wind time: --cloud-time, else its skycalCloudTimeS
// attribute, else 0. `verbose`: progress on stderr.
cloudfit::SkyCloudFit RunSkyCloudFit(const FitCloudOptions& o, const std::vector<fit::Reference>& refs,
                                     const render::Preset& init, const fit::FitOptions& fo, render::SkyRenderer& renderer,
                                     const std::vector<const fit::ProbeSamples*>& probes, const LoadedCloudShapes* shapes);

// fit.json's `clouds` object (a day: `keyframes`, one per reference in time order):
// cloudfit::CloudReportJson with these options.
nlohmann::json CloudReportJson(const FitCloudOptions& o, const cloudfit::SkyCloudFit& f);


// With fitted clouds: the preset gains the clouds section (fitted lighting; a day: the
// earliest reference's) naming a copy of the weather map written beside preset.json as
// <stem>.weather.exr; a day of references also writes <stem>.cloud_keyframes.json
// (cloudfit::CloudDayKeyframesJson), which `skycal export` turns into one keyframe per time of day.
void AttachFittedClouds(const cloudfit::SkyCloudFit& f, const LoadedCloudShapes& shapes,
                        const std::filesystem::path& preset_json, render::Preset* preset);

}  // namespace skycal::cli
