// The clouds part of `skycal export` (issue 11): per preset with a `clouds` section,
// GAME_DIR/<preset>/clouds.json (every field with its unit, bounds and description: the
// fitted lighting included) and its weather map copied to GAME_DIR/<preset>/weather.exr;
// over the timed presets with clouds, GAME_DIR/cloud_keyframes.csv and .json: the shape
// of FFXV's weather file, one row per TIME_OF_DAY key, one column per cloud lighting
// parameter, the unit in each column's header ("extinction [1/m]").
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/render/preset.h"

namespace skycal::cli {

// A number for the keyframe CSVs: 9 significant digits (every float survives the round trip).
std::string CsvNumber(double v);

// Writes the preset's cloud files under out_root/<preset.name>/ and records them in
// `files` ("clouds", "weather_map"); nothing without a clouds section. Throws skycal::Error
// naming the preset file and field on a bad section or weather map.
void ExportPresetClouds(const render::Preset& preset, const std::string& preset_path,
                        const std::filesystem::path& out_root, nlohmann::json* files);

// The cloud keyframe table over `keyed` (sorted by time, each with a finite time of day);
// presets without clouds are listed in `skipped`. Nothing when none has clouds.
void ExportCloudKeyframes(const std::vector<const render::Preset*>& keyed, const std::filesystem::path& out_root,
                          nlohmann::json* skipped);

}  // namespace skycal::cli
