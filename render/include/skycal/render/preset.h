// A sky preset: every parameter of the game's sky model with units, bounds and defaults,
// plus the RGB LUTs (stored as EXR files next to the preset JSON).
#pragma once
#include <array>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "../../../model/limits.glsl.h"

namespace skycal::render {

enum class ModelVariant { kFfxv, kFfxvIso };
const char* ToString(ModelVariant v);
// Throws skycal::Error naming `what` unless `name` is "ffxv" or "ffxv-iso".
ModelVariant ParseModelVariant(const std::string& name, const std::string& what);

// Grid limits: the Vulkan renderer holds a frame's LUT slice (3 tables x columns) in a
// uniform block sized by render/model/limits.glsl.h.
inline constexpr int kMaxLutColumns = SC_MAX_LUT_COLUMNS;
inline constexpr int kMaxLutRows = 1024;

// LUT grid (node-centred, see render/model/sky_model.glsl.h for the mapping).
struct LutGrid {
  int n_theta = 37;              // rows: sun zenith 0 .. theta_max_deg, linear in cos(zenith)
  int n_gamma = 32;              // columns: sqrt(sin(elevation)) 0 .. 1
  double theta_max_deg = 108.0;  // 90 + 18: the end of astronomical twilight
};

struct SkyLuts {
  LutGrid grid;
  // Each n_theta * n_gamma * 3 floats, row-major (row = sun zenith), unit cd/m^2 * sr.
  std::vector<float> rayleigh, mie, isotropic;
  // n_theta * 3 floats: direct-sun transmittance per sun zenith row, dimensionless.
  std::vector<float> sun_transmittance;

  void Resize(const LutGrid& g);  // zero-filled tables for the grid
  size_t table_size() const { return static_cast<size_t>(grid.n_theta) * grid.n_gamma * 3; }
};

// Every scalar the model takes. Units and bounds live in the parameter table
// (PresetParameterSpecs), the single source the JSON reader, writer and validator share.
struct Preset {
  std::string name = "unnamed";
  ModelVariant variant = ModelVariant::kFfxv;
  double haziness_g = 0.8;                  // Cornette-Shanks g, 1
  double overcast_weight = 0.0;             // 1
  double overcast_zenith_cd_m2 = 4000.0;    // cd/m^2
  double sun_illuminance_lux = 128000.0;    // lux at normal incidence, top of atmosphere
  std::array<double, 3> sun_tint_rgb = {1.0, 1.0, 1.0};  // 1
  double sun_angular_radius_deg = 0.2666;   // deg (mean solar semi-diameter)
  double sun_limb_darkening = 0.6;          // linear limb-darkening coefficient u, 1
  double ground_albedo = 0.1;               // 1, diffuse ground below the horizon
  double time_of_day_h = std::numeric_limits<double>::quiet_NaN();  // hours [0, 24), NaN: none
  SkyLuts luts;
  // The preset's `clouds` section as JSON text, carried through unchanged (LoadPreset
  // fills it, SavePreset writes it back); empty when the preset has none. The clouds
  // module (above render) parses and validates it: clouds::ParseCloudSectionText.
  std::string clouds_json;
};

struct ParamSpec {
  const char* name;
  const char* unit;
  double min, max, default_value;
  int components;  // 1 or 3 (RGB)
  const char* description;
  double* (*field)(Preset&);
};
const std::vector<ParamSpec>& PresetParameterSpecs();

// Throws skycal::Error naming `origin` (file) and the field when a value is non-finite,
// out of its bounds, or a LUT is malformed (wrong size, negative or non-finite texel).
void ValidatePreset(const Preset& preset, const std::string& origin);

// JSON <-> Preset (parameters only; `lut_files` names the LUT EXRs).
nlohmann::json PresetToJson(const Preset& preset, const std::string& lut_stem);
// Reads a preset JSON and its LUT EXRs (paths relative to the JSON's directory).
Preset LoadPreset(const std::string& path);
// The files a preset consists of: its JSON, the LUT EXRs it names and the weather-map EXR
// its `clouds` section names (as far as the JSON can be read; an unreadable JSON gives
// just its own path). Verbs list them as inputs so
// that no output replaces a preset's LUT (file_safety.h).
std::vector<std::string> PresetFiles(const std::string& json_path);
// The files SavePreset(json_path) writes for a preset of `variant`.
std::vector<std::string> PresetOutputFiles(const std::string& json_path, ModelVariant variant);
// Writes `<dir>/<stem>.json` and `<dir>/<stem>.<lut>.exr`, each atomically. `extra`
// (optional) adds top-level keys to the JSON, e.g. the fit's provenance.
void SavePreset(const Preset& preset, const std::string& json_path, const nlohmann::json* extra = nullptr);

// The LUT grid's mapping on the host (the shaders' is lut_row / lut_col of
// render/model/sky_model.glsl.h, which a test holds these to):
//   row = (1 - cos ts) / (1 - cos ts_max) (n_theta - 1), col = sqrt(sin e) (n_gamma - 1).
// 1 - cos(ts_max), ts_max = grid.theta_max_deg.
double LutOneMinusCosThetaMax(const LutGrid& grid);
// The fractional row of a sun height cos(ts) = sun.y, clamped to [0, n_theta - 1].
double LutRowPosition(const LutGrid& grid, double sun_height);
// The inverses at the nodes: cos(sun zenith) of a row, sin(view elevation) of a column.
double LutRowSunHeight(const LutGrid& grid, int row);
double LutColumnViewHeight(const LutGrid& grid, int col);
// Where the LUT nodes sit: the sun zenith angle of a row and the view elevation of a
// column, radians.
double LutRowSunZenithRad(const LutGrid& grid, int row);
double LutColumnElevationRad(const LutGrid& grid, int col);

// Direct-sun transmittance at a sun zenith angle (radians), between rows in the LUT's row
// coordinate (linear in cos(sun zenith)): geometric where both rows are non-zero.
std::array<double, 3> SunTransmittance(const SkyLuts& luts, double sun_zenith_rad);

}  // namespace skycal::render
