#include "skycal/export/export_clouds.h"

#include <algorithm>
#include <cmath>
#include <sstream>


#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"

namespace skycal::exporter {
namespace fs = std::filesystem;

std::string CsvNumber(double v) {
  std::ostringstream ss;
  ss.precision(9);
  ss << v;
  return ss.str();
}

void ExportPresetClouds(const render::Preset& p, const std::string& preset_path, const fs::path& out_root,
                        nlohmann::json* files) {
  if (p.clouds_json.empty()) return;
  clouds::CloudParams params = clouds::ParseCloudSectionText(p.clouds_json, preset_path);
  if (!params.weather_map.empty()) {
    const std::string src = (fs::path(preset_path).parent_path() / params.weather_map).string();
    const clouds::WeatherMap map = clouds::LoadWeatherMap(src, params.weather_extent_m);
    clouds::SaveWeatherMap(map, (out_root / p.name / "weather.exr").string());
    params.weather_map = "weather.exr";
    (*files)["weather_map"] = p.name + "/weather.exr";
  }
  WriteJsonFileAtomically(out_root / p.name / "clouds.json", clouds::CloudSectionToJson(params));
  (*files)["clouds"] = p.name + "/clouds.json";
}

namespace {

struct CloudKey {
  double time_h = 0.0;
  std::string preset, source;  // the preset's name; where the key came from (for errors)
  cloudfit::CloudLighting lighting{};
};

// The keys of a day fit's <stem>.cloud_keyframes.json (written by fit --clouds).
std::vector<CloudKey> DayKeys(const render::Preset& p, const fs::path& file) {
  const nlohmann::json j = ReadJsonFile(file.string());
  const std::string where = file.string();
  if (!j.contains("keys") || !j["keys"].is_array() || j["keys"].empty()) {
    throw Error(where + ": 'keys': expected a non-empty array of cloud keyframes");
  }
  // Parameters a key does not list keep the preset's section (fit writes all of them).
  const cloudfit::CloudLighting base = cloudfit::GetCloudLighting(clouds::ParseCloudSectionText(p.clouds_json, where));
  std::vector<CloudKey> out;
  for (size_t k = 0; k < j["keys"].size(); ++k) {
    const nlohmann::json& key = j["keys"][k];
    const std::string at = where + ": keys[" + std::to_string(k) + "]";
    if (!key.contains("time_of_day_h") || !key["time_of_day_h"].is_number()) {
      throw Error(at + ".time_of_day_h: expected hours in [0, 24)");
    }
    CloudKey c;
    c.time_h = key["time_of_day_h"].get<double>();
    if (!(c.time_h >= 0.0 && c.time_h < 24.0)) throw Error(at + ".time_of_day_h: expected hours in [0, 24)");
    c.preset = p.name;
    c.source = at;
    c.lighting = base;
    if (!key.contains("lighting") || !key["lighting"].is_object()) throw Error(at + ".lighting: expected an object");
    clouds::CloudParams params;
    for (int i = 0; i < cloudfit::kCloudLightingParameters; ++i) {
      const char* name = cloudfit::CloudLightingNames()[i];
      if (!key["lighting"].contains(name)) continue;
      const nlohmann::json& v = key["lighting"][name];
      const clouds::CloudParamSpec& s = cloudfit::CloudLightingSpec(i);
      if (!v.is_number() || !(v.get<double>() >= s.min && v.get<double>() <= s.max)) {
        throw Error(at + ".lighting." + name + ": expected a number in [" + CsvNumber(s.min) + ", " + CsvNumber(s.max) +
                    "] " + s.unit + ", got " + v.dump());
      }
      c.lighting[i] = v.get<double>();
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace

void ExportCloudKeyframes(const std::vector<render::Preset>& presets, const std::vector<std::string>& paths,
                          const fs::path& out_root, nlohmann::json* skipped) {
  std::vector<CloudKey> keys;
  std::string without;
  for (size_t i = 0; i < presets.size(); ++i) {
    const render::Preset& p = presets[i];
    const fs::path path(paths.at(i));
    const fs::path day = path.parent_path() / (path.stem().string() + ".cloud_keyframes.json");
    if (!p.clouds_json.empty() && fs::is_regular_file(day)) {
      for (const CloudKey& k : DayKeys(p, day)) keys.push_back(k);
    } else if (!std::isfinite(p.time_of_day_h)) {
      continue;  // untimed: no key (the sky's keyframe table says so)
    } else if (p.clouds_json.empty()) {
      without += (without.empty() ? "'" : ", '") + p.name + "'";
    } else {
      CloudKey k;
      k.time_h = p.time_of_day_h;
      k.preset = p.name;
      k.source = "preset '" + p.name + "'";
      k.lighting = cloudfit::GetCloudLighting(clouds::ParseCloudSectionText(p.clouds_json, k.source));
      keys.push_back(k);
    }
  }
  if (keys.empty()) {
    skipped->push_back({{"block", "cloud keyframe table"},
                        {"reason", "no timed preset has a clouds section and no preset is a day fit with clouds"}});
    return;
  }
  if (!without.empty()) {
    skipped->push_back({{"block", "cloud keyframes of " + without}, {"reason", "no clouds section (a cloud fit writes it)"}});
  }
  std::stable_sort(keys.begin(), keys.end(), [](const CloudKey& a, const CloudKey& b) { return a.time_h < b.time_h; });
  for (size_t k = 1; k < keys.size(); ++k) {
    if (keys[k].time_h == keys[k - 1].time_h) {
      throw Error(keys[k - 1].source + " and " + keys[k].source + " have the same time of day " +
                  CsvNumber(keys[k].time_h) + " h (one cloud keyframe per time)");
    }
  }
  std::vector<std::string> header = {"time_of_day_h", "preset"};
  nlohmann::json units = {{"time_of_day_h", "h"}};
  for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
    const clouds::CloudParamSpec& s = cloudfit::CloudLightingSpec(k);
    header.push_back(std::string(s.name) + " [" + s.unit + "]");
    units[s.name] = s.unit;
  }
  std::string csv;
  for (size_t c = 0; c < header.size(); ++c) csv += (c ? "," : "") + header[c];
  csv += "\n";
  nlohmann::json rows = nlohmann::json::array();
  for (const CloudKey& key : keys) {
    nlohmann::json row = {{"time_of_day_h", key.time_h}, {"preset", key.preset}};
    csv += CsvNumber(key.time_h) + "," + key.preset;
    for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
      csv += "," + CsvNumber(key.lighting[k]);
      row[cloudfit::CloudLightingNames()[k]] = key.lighting[k];
    }
    csv += "\n";
    rows.push_back(row);
  }
  WriteFileAtomically(out_root / "cloud_keyframes.csv", csv);
  WriteJsonFileAtomically(out_root / "cloud_keyframes.json", {{"columns", header}, {"units", units}, {"keys", rows}});
}

}  // namespace skycal::exporter
