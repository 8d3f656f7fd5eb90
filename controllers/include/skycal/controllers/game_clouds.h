// The clouds of a game render (game_render.h): which cloud parameters, weather map and noise
// a render uses. The clouds come from the preset's `clouds` section, or the bundled cloudy
// default's when the preset has none (datasets/presets/default_cloudy.json); the weather map
// from GameCloudOptions::weather_map, else the one the section names (next to its preset).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/core/file_safety.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {

// Volumetric clouds as Horizon Zero Dawn draws them (Schneider, "The Real-Time Volumetric
// Cloudscapes of Horizon: Zero Dawn", SIGGRAPH 2015), composited over the sky.
struct GameCloudOptions {
  bool enabled = false;         // false: the sky alone, and the fields below are not read
  std::string weather_map;      // RGB EXR (coverage, precipitation, type) instead of the section's; empty: the section's
  double time_s = 0.0;          // seconds in [-1e7, 1e7]: the wind moves the clouds by speed x time
  clouds::MarchOptions march;   // samples and optimisations of the march (HZD's by default)
};

std::string DefaultCloudyPresetPath();  // datasets/presets/default_cloudy.json in the data directory (core/data_dir.h)
inline constexpr uint64_t kCloudNoiseSeed = 1;  // the noise every render uses (cached)

// Files a cloud render reads besides the preset's own (for file_safety.h): the weather map
// named by GameCloudOptions::weather_map, and the bundled preset's files. Empty when clouds
// are off.
std::vector<NamedPath> CloudInputs(const GameCloudOptions& o);

struct CloudInputsLoaded {
  clouds::CloudParams params;
  std::string params_origin;   // the file the section came from
  clouds::WeatherMap weather;
  std::string weather_origin;  // the EXR it came from
  std::shared_ptr<const clouds::CloudNoise> noise;  // never null
};
// Parses the section and loads the weather map and the noise. Throws skycal::Error naming
// the file and field: unknown or out-of-range cloud fields, a weather map of the wrong
// size or channels, a NaN texel, no weather map at all.
CloudInputsLoaded LoadCloudInputs(const GameCloudOptions& o, const render::Preset& preset, const std::string& preset_path);

// A preset as inputs for file_safety.h: its JSON (role `role`) and every LUT EXR it names
// (role "`role` PRESET's LUT").
std::vector<NamedPath> PresetFileInputs(const std::string& role, const std::string& preset_json);

}  // namespace skycal::controllers
