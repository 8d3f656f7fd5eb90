// The game export: the game's tables from calibrated presets: LUT textures as half-float
// EXRs under one pre-exposure scale (FFXV multiplies exposure into every light source so
// FP16 never clamps: Miyamoto & Driancourt 2016), and a time-of-day keyframe table (CSV + JSON, one row
// per key, one column per parameter: the shape of FFXV's weather file). Where a preset's
// provenance names the sun direction it was fitted at (fit writes
// provenance.final_errors[i].sun_direction), also: the sun's illuminance at the ground per
// key, the sky's SH-9 (FFXV's diffuse lighting) and a fog colour and blurred
// fog lat-long (Forza Horizon 3's fog cubemap: Wood, GDC).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/render/renderer.h"

namespace skycal::exporter {

struct ExportOptions {
  std::vector<std::string> presets;  // preset JSONs
  std::string out_dir;               // written atomically
  double headroom = 0.25;            // largest scaled LUT value <= headroom * 65504 (FP16 max)
  render::Backend backend = render::Backend::kVulkan;  // renders the sky for SH-9 and fog
  double fog_sigma_deg = 15.0;       // Gaussian blur of the fog lat-long, degrees, (0, 30]
  bool report = true;                // write GAME_DIR/report.html (skycal report)
  bool verbose = true;               // progress lines on stderr ([export] ...); skycal bench turns them off
  bool IsValid(std::string* why) const;
};

// The controller: writes every table of the presets into options.out_dir (staged, replaced
// atomically; core/staged_directory.h), GAME_DIR/report.html when options.report, and
// returns the manifest with "out". Throws skycal::Error.
nlohmann::json ExportGameTables(const ExportOptions& options);

}  // namespace skycal::exporter
