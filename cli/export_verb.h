// `skycal export`: the game's tables from calibrated presets: LUT textures as half-float
// EXRs under one pre-exposure scale (FFXV multiplies exposure into every light source so
// FP16 never clamps, DESIGN.md 1.1), and a time-of-day keyframe table (CSV + JSON, one row
// per key, one column per parameter: the shape of FFXV's weather file).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace skycal::cli {

struct ExportOptions {
  std::vector<std::string> presets;  // preset JSONs
  std::string out_dir;               // written atomically
  double headroom = 0.25;            // largest scaled LUT value <= headroom * 65504 (FP16 max)
  bool IsValid(std::string* why) const;
};

nlohmann::json RunExportImpl(const ExportOptions& options);
int RunExport(int argc, char** argv);

}  // namespace skycal::cli
