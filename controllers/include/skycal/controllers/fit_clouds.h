// The clouds stage of the fit controller (docs/cloud-fitting.md): the mode (auto|on|off), the
// known shapes (a cloud preset, the wind time), the decision, the joint fit through
// cloudfit::FitSkyAndClouds, and fit.json's `clouds` object. Kept apart from
// fit_controller.cc so the sky-only pipeline reads as before. Errors name the fields.
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

namespace skycal::controllers {

struct FitCloudOptions {
  std::string mode = "auto";        // auto|on|off (cloudfit::CloudMode)
  std::string preset;               // PRESET.json: a clouds section (shapes + start lighting); empty: none
  // The wind time of every reference, seconds; unset: each reference's skycalCloudTimeS
  // attribute (render --clouds --cloud-time writes it), else 0.
  std::optional<double> time_s;
  double day_smoothness = 0.02;     // the day's prior over time of day (CloudLightingOptions)
  int samples = 256;                // cloud pixels in the Jacobian (CloudLightingOptions)
  int max_iterations = 100;         // of the lighting solve (CloudLightingOptions)
  bool fit_sun_scale = false;       // the clouds' sun scale free (CloudLightingOptions)
  bool values_from_renderer = true; // the solve's values by frame renders, else at the samples (CloudLightingOptions)
  bool restart_at_bounds = false;   // a parameter left at a bound solved again from the other side (CloudLightingOptions)
  bool release_inseparable = false;  // the inseparable holds released after the solve, kept when lower (CloudLightingOptions)
  double start_prior = 0.0;          // weight of the pull toward the solve's start (CloudLightingOptions)
  std::vector<std::string> hold;    // cloud lighting parameters held at the preset's values
  // The sky stage's pixels: false, those clear through the known shapes (exact for shapes
  // that are the scene's); true, the photo's own clear pixels (cloud probability < 0.5, as
  // FitControllerOptions::cloud_mask): for shapes inverted from the photo, whose cloud near
  // the horizon covers every pixel of some LUT columns, which the sky stage would then
  // extrapolate from their neighbours' bilinear tails.
  bool sky_pixels_from_photo = false;
  // With sky_pixels_from_photo, the colour ramp's allowance for the haze round the sun in that
  // cloud mask (capture::CloudMaskOptions::sun_boost, [0, 5]; unset: the ramp's own; no effect
  // on a frame that carries its own mask.cloud channel, which is used as it is). The
  // allowance keeps a clear sky whitened by the sun from being called cloud; the atmosphere
  // wants pixels that are surely clear, and with the allowance a thin cloud by the sun passes
  // for clear sky and brightens the fitted aureole (bench/results/weather_inversion.md, "The
  // clear sky by the sun").
  std::optional<double> sky_pixels_sun_boost;
  // The map refined after the lighting solve and solved on (CloudLightingOptions, not owned;
  // null: none): calibrate's precipitation read from the photo's light. The exported preset
  // carries the refined map.
  cloudfit::ShapeRefinement* refine_shapes = nullptr;
  int iterations_after_refinement = 1;
  // False and the field (FitCloudOptions::, CloudLightingOptions::), its value and the
  // expectation in *why.
  bool IsValid(std::string* why) const;
};

// Files the clouds part reads (the cloud preset and its weather map) for file_safety.h.
std::vector<NamedPath> FitCloudInputs(const FitCloudOptions& o);

// The known shapes of FitCloudOptions::preset, loaded (noise from its seed cache); null without one.
struct LoadedCloudShapes {
  std::string origin, weather_origin;
  std::shared_ptr<const clouds::CloudNoise> noise;
  clouds::WeatherMap weather;
  cloudfit::KnownCloudShapes shapes;  // points into noise and weather (do not copy)
};
std::unique_ptr<LoadedCloudShapes> LoadFitCloudShapes(const FitCloudOptions& o);

// Runs the fit with or without clouds (the decision first: a bad mode "on" fails before
// any solve). Each reference's wind time: FitCloudOptions::time_s, else its skycalCloudTimeS
// attribute, else 0. fo.verbose: progress on stderr.
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

}  // namespace skycal::controllers
