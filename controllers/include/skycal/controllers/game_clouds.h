// The cloud part of `skycal render --clouds`: which cloud parameters, weather map and noise
// a render uses, and the march options from the command line. The clouds come from the
// preset's `clouds` section, or the bundled cloudy default's when the preset has none
// (datasets/presets/default_cloudy.json); the weather map from --weather-map, else the one
// the section names (next to its preset).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/core/file_safety.h"
#include "skycal/render/preset.h"

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

std::string DefaultCloudyPresetPath();  // datasets/presets/default_cloudy.json in the data directory (core/data_dir.h)
inline constexpr uint64_t kCloudNoiseSeed = 1;  // the noise every render uses (cached)

// The march options the command line asks for; throws skycal::Error naming the option
// and the field ("--cloud-steps: steps_zenith = 0 (expected an integer in [1, 4096])").
clouds::MarchOptions CloudMarchOptions(const CloudOptions& o);

// Files a cloud render reads (for file_safety.h): --weather-map, and the bundled preset's
// files when the preset has no section. Empty when clouds are off.
std::vector<NamedPath> CloudInputs(const CloudOptions& o, const std::string& preset_path);

struct CloudInputsLoaded {
  clouds::CloudParams params;
  std::string params_origin;   // the file the section came from
  clouds::WeatherMap weather;
  std::string weather_origin;  // the EXR it came from
  clouds::CloudNoise noise;
};
// Parses the section and loads the weather map and the noise. Throws skycal::Error naming
// the file and field: unknown or out-of-range cloud fields, a weather map of the wrong
// size or channels, a NaN texel, no weather map at all.
CloudInputsLoaded LoadCloudInputs(const CloudOptions& o, const render::Preset& preset, const std::string& preset_path);

}  // namespace skycal::cli
