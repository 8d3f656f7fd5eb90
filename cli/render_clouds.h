// The cloud flags of `skycal render --clouds` as given (the march ones as text, so that a bad
// value names its flag), and their translation into the controllers library's options. What
// a cloud render reads is the library's (controllers/game_clouds.h).
#pragma once
#include <optional>
#include <string>

#include "skycal/clouds/cloud_params.h"
#include "skycal/controllers/game_clouds.h"

namespace skycal::cli {

struct CloudOptions {
  bool enabled = false;                  // --clouds
  std::string weather_map;               // --weather-map W.exr (overrides the section's)
  double time_s = 0.0;                   // --cloud-time S: wind offset = speed x time
  std::optional<std::string> steps;      // --cloud-steps ZENITH,HORIZON
  std::optional<std::string> light_samples;  // --cloud-light-samples N
  bool naive = false;                    // --cloud-naive: every march optimisation off
  // --cloud-cheap-light-opacity O: opacity (1) past which light samples are base-shape only
  // (HZD: 0.3, the default; 0.6 halves the added error at the same lavapipe time, docs/benchmarks.md).
  std::optional<std::string> cheap_light_opacity;
};

// The march options the command line asks for; throws skycal::Error naming the option
// and the field ("--cloud-steps: steps_zenith = 0 (expected an integer in [1, 4096])").
clouds::MarchOptions CloudMarchOptions(const CloudOptions& o);

// The library's cloud options for these flags, with `march` (CloudMarchOptions's).
controllers::GameCloudOptions ToGameClouds(const CloudOptions& o, const clouds::MarchOptions& march);

}  // namespace skycal::cli
