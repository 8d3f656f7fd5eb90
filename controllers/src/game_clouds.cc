#include "skycal/controllers/game_clouds.h"

#include <filesystem>

#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"

namespace skycal::controllers {
namespace fs = std::filesystem;

std::string DefaultCloudyPresetPath() { return DataPath("datasets/presets/default_cloudy.json"); }

std::vector<NamedPath> PresetFileInputs(const std::string& role, const std::string& preset_json) {
  std::vector<NamedPath> inputs;
  const std::vector<std::string> files = render::PresetFiles(preset_json);  // the JSON, then every LUT EXR it names
  for (size_t i = 0; i < files.size(); ++i) inputs.push_back({i == 0 ? role : role + " " + preset_json + "'s LUT", files[i]});
  return inputs;
}

std::vector<NamedPath> CloudInputs(const GameCloudOptions& o) {
  std::vector<NamedPath> inputs;
  if (!o.enabled) return inputs;
  if (!o.weather_map.empty()) inputs.push_back({"GameCloudOptions::weather_map", o.weather_map});
  for (const NamedPath& p : PresetFileInputs("bundled cloudy preset", DefaultCloudyPresetPath())) inputs.push_back(p);
  return inputs;  // the preset's own files (its weather map included) are the render's preset inputs
}

CloudInputsLoaded LoadCloudInputs(const GameCloudOptions& o, const render::Preset& preset, const std::string& preset_path) {
  CloudInputsLoaded in;
  std::string section = preset.clouds_json, section_path = preset_path;
  if (section.empty()) {  // the bundled cloudy default's section
    section_path = DefaultCloudyPresetPath();
    section = render::LoadPreset(section_path).clouds_json;
    if (section.empty()) throw Error(section_path + ": the bundled cloudy preset has no clouds section");
  }
  in.params = clouds::ParseCloudSectionText(section, section_path);
  in.params_origin = section_path;
  if (!o.weather_map.empty()) {
    in.weather_origin = o.weather_map;
  } else if (!in.params.weather_map.empty()) {
    in.weather_origin = (fs::path(section_path).parent_path() / in.params.weather_map).string();
  } else {
    throw Error(section_path + ": field 'clouds.weather_map' is missing and no GameCloudOptions::weather_map was given "
                "(expected an RGB EXR: coverage, precipitation, type)");
  }
  in.weather = clouds::LoadWeatherMap(in.weather_origin, in.params.weather_extent_m);
  in.noise = clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
  return in;
}

}  // namespace skycal::controllers
