#include "export_clouds.h"

#include <sstream>


#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"

namespace skycal::cli {
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

void ExportCloudKeyframes(const std::vector<const render::Preset*>& keyed, const fs::path& out_root,
                          nlohmann::json* skipped) {
  std::vector<const render::Preset*> with;
  std::string without;
  for (const render::Preset* p : keyed) {
    if (p->clouds_json.empty()) {
      without += (without.empty() ? "'" : ", '") + p->name + "'";
    } else {
      with.push_back(p);
    }
  }
  if (with.empty()) {
    skipped->push_back({{"block", "cloud keyframe table"}, {"reason", "no timed preset has a clouds section"}});
    return;
  }
  if (!without.empty()) {
    skipped->push_back({{"block", "cloud keyframes of " + without}, {"reason", "no clouds section (fit --clouds)"}});
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
  for (const render::Preset* p : with) {
    const clouds::CloudParams params = clouds::ParseCloudSectionText(p->clouds_json, "preset '" + p->name + "'");
    const cloudfit::CloudLighting l = cloudfit::GetCloudLighting(params);
    nlohmann::json row = {{"time_of_day_h", p->time_of_day_h}, {"preset", p->name}};
    csv += CsvNumber(p->time_of_day_h) + "," + p->name;
    for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
      csv += "," + CsvNumber(l[k]);
      row[cloudfit::CloudLightingNames()[k]] = l[k];
    }
    csv += "\n";
    rows.push_back(row);
  }
  WriteFileAtomically(out_root / "cloud_keyframes.csv", csv);
  WriteJsonFileAtomically(out_root / "cloud_keyframes.json", {{"columns", header}, {"units", units}, {"keys", rows}});
}

}  // namespace skycal::cli
