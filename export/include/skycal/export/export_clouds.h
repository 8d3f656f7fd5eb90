// The clouds part of `skycal export` (docs/cloud-fitting.md, "Export"): per preset with a `clouds` section,
// GAME_DIR/<preset>/clouds.json (every field with its unit, bounds and description: the
// fitted lighting included) and its weather map copied to GAME_DIR/<preset>/weather.exr;
// over the timed presets with clouds and the day fits, GAME_DIR/cloud_keyframes.csv and .json: the shape
// of FFXV's weather file, one row per TIME_OF_DAY key, one column per cloud lighting
// parameter, the unit in each column's header ("extinction [1/m]").
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/render/preset.h"

namespace skycal::exporter {

// A number for the keyframe CSVs: 9 significant digits (every float survives the round trip).
std::string CsvNumber(double v);

// Writes the preset's cloud files under out_root/<preset.name>/ and records them in
// `files` ("clouds", "weather_map"); nothing without a clouds section. Throws skycal::Error
// naming the preset file and field on a bad section or weather map.
void ExportPresetClouds(const render::Preset& preset, const std::string& preset_path,
                        const std::filesystem::path& out_root, nlohmann::json* files);

// The cloud keyframe table over `presets` (paths[i] the file of presets[i]): a day fit's
// preset (fit --clouds over several references) gives one key per reference from the
// <stem>.cloud_keyframes.json beside it; any other timed preset with a clouds section one
// key at its time_of_day_h. Keys sorted by time; two at one time are refused naming both.
// Timed presets without clouds are listed in `skipped`; nothing when no key exists.
void ExportCloudKeyframes(const std::vector<render::Preset>& presets, const std::vector<std::string>& paths,
                          const std::filesystem::path& out_root, nlohmann::json* skipped);

}  // namespace skycal::exporter
