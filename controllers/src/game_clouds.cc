#include "render_clouds.h"

#include <filesystem>

#include "option_values.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;

std::string DefaultCloudyPresetPath() { return DataPath("datasets/presets/default_cloudy.json"); }

clouds::MarchOptions CloudMarchOptions(const CloudOptions& o) {
  clouds::MarchOptions m = o.naive ? clouds::MarchOptions::Naive() : clouds::MarchOptions{};
  std::string why;
  if (o.steps) {
    const std::vector<double> v = ParseNumberList(*o.steps, "--cloud-steps");
    if (v.size() != 2) throw Error("--cloud-steps: expected ZENITH,HORIZON (two sample counts), got '" + *o.steps + "'");
    for (double s : v) {
      if (s != std::floor(s) || std::abs(s) > 1e9) throw Error("--cloud-steps: expected integers, got '" + *o.steps + "'");
    }
    m.steps_zenith = static_cast<int>(v[0]);
    m.steps_horizon = static_cast<int>(v[1]);
    if (!m.IsValid(&why)) throw Error("--cloud-steps: " + why);
  }
  if (o.light_samples) {
    m.light_samples = ParseInteger(*o.light_samples, "--cloud-light-samples");
    if (!m.IsValid(&why)) throw Error("--cloud-light-samples: " + why);
  }
  if (o.cheap_light_opacity) {
    m.cheap_light_opacity = ParseNumber(*o.cheap_light_opacity, "--cloud-cheap-light-opacity");
    if (!m.IsValid(&why)) throw Error("--cloud-cheap-light-opacity: " + why);
  }
  return m;
}

std::vector<NamedPath> CloudInputs(const CloudOptions& o, const std::string& preset_path) {
  std::vector<NamedPath> inputs;
  if (!o.enabled) return inputs;
  if (!o.weather_map.empty()) inputs.push_back({"--weather-map", o.weather_map});
  for (const NamedPath& p : PresetInputs("bundled cloudy preset", DefaultCloudyPresetPath())) inputs.push_back(p);
  (void)preset_path;  // the preset's own files (weather map included) are render's --preset inputs
  return inputs;
}

CloudInputsLoaded LoadCloudInputs(const CloudOptions& o, const render::Preset& preset, const std::string& preset_path) {
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
    throw Error(section_path + ": field 'clouds.weather_map' is missing and no --weather-map was given (expected an RGB EXR: "
                "coverage, precipitation, type)");
  }
  in.weather = clouds::LoadWeatherMap(in.weather_origin, in.params.weather_extent_m);
  in.noise = clouds::LoadOrGenerateCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
  return in;
}

}  // namespace skycal::cli
