#include "skycal/render/preset.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <thread>
#include <nlohmann/json.hpp>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "skycal/core/interrupt_cleanup.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"
#include "skycal/core/version.h"

namespace skycal::render {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
constexpr const char* kFormat = "skycal-preset";
constexpr int kFormatVersion = 1;
constexpr const char* kLutNames[3] = {"rayleigh", "mie", "isotropic"};

std::vector<float>& LutTable(SkyLuts& luts, int i) {
  return i == 0 ? luts.rayleigh : (i == 1 ? luts.mie : luts.isotropic);
}
const std::vector<float>& LutTable(const SkyLuts& luts, int i) {
  return i == 0 ? luts.rayleigh : (i == 1 ? luts.mie : luts.isotropic);
}

std::string Field(const std::string& origin, const std::string& field) {
  return origin + ": field '" + field + "'";
}
}  // namespace

const char* ToString(ModelVariant v) { return v == ModelVariant::kFfxv ? "ffxv" : "ffxv-iso"; }

ModelVariant ParseModelVariant(const std::string& name, const std::string& what) {
  if (name == "ffxv") return ModelVariant::kFfxv;
  if (name == "ffxv-iso") return ModelVariant::kFfxvIso;
  throw Error(what + ": unknown model variant '" + name + "' (expected ffxv or ffxv-iso)");
}

void SkyLuts::Resize(const LutGrid& g) {
  grid = g;
  rayleigh.assign(table_size(), 0.0f);
  mie.assign(table_size(), 0.0f);
  isotropic.assign(table_size(), 0.0f);
  sun_transmittance.assign(static_cast<size_t>(g.n_theta) * 3, 1.0f);
}

const std::vector<ParamSpec>& PresetParameterSpecs() {
  static const std::vector<ParamSpec> specs = {
      {"haziness_g", "1", 0.0, 0.999, 0.8, 1,
       "Cornette-Shanks asymmetry of the Mie term (FFXV 'haziness'); 0 isotropic-ish, ->1 peaked",
       [](Preset& p) { return &p.haziness_g; }},
      {"overcast_weight", "1", 0.0, 1.0, 0.0, 1,
       "blend weight of the CIE standard overcast sky over the LUT sky",
       [](Preset& p) { return &p.overcast_weight; }},
      {"overcast_zenith_luminance", "cd/m^2", 0.0, 1.0e6, 4000.0, 1,
       "zenith luminance L_z of the CIE overcast term: L = L_z (1 + 2 sin(elevation)) / 3",
       [](Preset& p) { return &p.overcast_zenith_cd_m2; }},
      {"sun_illuminance", "lux", 0.0, 2.0e5, 128000.0, 1,
       "solar illuminance at normal incidence above the atmosphere (solar constant ~128 klux); "
       "the disc shows it times sun_tint_rgb times the LUT's sun transmittance",
       [](Preset& p) { return &p.sun_illuminance_lux; }},
      {"sun_tint_rgb", "1", 0.0, 10.0, 1.0, 3, "RGB multiplier of the sun's illuminance",
       [](Preset& p) { return p.sun_tint_rgb.data(); }},
      {"sun_angular_radius", "deg", 0.01, 5.0, 0.2666, 1,
       "angular radius of the sun disc (0.2666 deg: mean solar semi-diameter)",
       [](Preset& p) { return &p.sun_angular_radius_deg; }},
      {"sun_limb_darkening", "1", 0.0, 1.0, 0.6, 1,
       "linear limb-darkening coefficient u: I(r)/I(0) = 1 - u (1 - cos_limb) (~0.6 in the visible)",
       [](Preset& p) { return &p.sun_limb_darkening; }},
      {"ground_albedo", "1", 0.0, 1.0, 0.1, 1,
       "diffuse albedo of the ground shown below the horizon, lit by the sun and the model sky",
       [](Preset& p) { return &p.ground_albedo; }},
  };
  return specs;
}

void ValidatePreset(const Preset& preset_in, const std::string& origin) {
  Preset preset = preset_in;  // specs hand out mutable pointers
  for (const ParamSpec& s : PresetParameterSpecs()) {
    const double* v = s.field(preset);
    for (int c = 0; c < s.components; ++c) {
      if (!std::isfinite(v[c]) || v[c] < s.min || v[c] > s.max) {
        throw Error(Field(origin, s.name) + " = " + FormatNumber(v[c]) + " is out of range (expected a finite value in [" +
                    FormatNumber(s.min) + ", " + FormatNumber(s.max) + "] " + s.unit + ")");
      }
    }
  }
  const LutGrid& g = preset.luts.grid;
  if (g.n_theta < 2 || g.n_gamma < 2 || g.n_theta > kMaxLutRows || g.n_gamma > kMaxLutColumns) {
    throw Error(Field(origin, "luts.grid") + ": expected 2.." + std::to_string(kMaxLutRows) + " rows and 2.." +
                std::to_string(kMaxLutColumns) + " columns, got " +
                std::to_string(g.n_theta) + " x " + std::to_string(g.n_gamma));
  }
  if (!std::isfinite(g.theta_max_deg) || g.theta_max_deg < 90.0 || g.theta_max_deg > 180.0) {
    throw Error(Field(origin, "luts.grid.theta_max_deg") + ": expected 90..180 degrees");
  }
  const int tables = preset.variant == ModelVariant::kFfxvIso ? 3 : 2;
  for (int t = 0; t < tables; ++t) {
    const auto& table = LutTable(preset.luts, t);
    if (table.size() != preset.luts.table_size()) {
      throw Error(Field(origin, std::string("luts.") + kLutNames[t]) + ": expected " +
                  std::to_string(preset.luts.table_size()) + " values, got " + std::to_string(table.size()));
    }
    for (size_t i = 0; i < table.size(); ++i) {
      if (!std::isfinite(table[i]) || table[i] < 0.0f) {
        const size_t texel = i / 3;
        throw Error(Field(origin, std::string("luts.") + kLutNames[t]) + ": texel (row " +
                    std::to_string(texel / g.n_gamma) + ", column " + std::to_string(texel % g.n_gamma) +
                    ") = " + FormatNumber(table[i]) + " (expected finite and >= 0)");
      }
    }
  }
  if (preset.luts.sun_transmittance.size() != static_cast<size_t>(g.n_theta) * 3) {
    throw Error(Field(origin, "luts.sun_transmittance") + ": expected " + std::to_string(g.n_theta * 3) + " values");
  }
  for (float t : preset.luts.sun_transmittance) {
    if (!std::isfinite(t) || t < 0.0f || t > 1.0f) {
      throw Error(Field(origin, "luts.sun_transmittance") + ": expected values in [0, 1], got " + FormatNumber(t));
    }
  }
}

json PresetToJson(const Preset& preset_in, const std::string& lut_stem) {
  Preset preset = preset_in;
  json params = json::object();
  for (const ParamSpec& s : PresetParameterSpecs()) {
    const double* v = s.field(preset);
    json value = s.components == 1 ? json(v[0]) : json(std::vector<double>(v, v + s.components));
    params[s.name] = {{"value", value}, {"unit", s.unit}, {"min", s.min}, {"max", s.max},
                      {"default", s.default_value}, {"description", s.description}};
  }
  json luts = {
      {"grid", {{"n_theta", preset.luts.grid.n_theta}, {"n_gamma", preset.luts.grid.n_gamma},
                {"theta_max_deg", preset.luts.grid.theta_max_deg},
                {"row_mapping", "cos(sun zenith) = 1 - row / (n_theta - 1) * (1 - cos(theta_max_deg))"},
                {"column_mapping", "sin(view elevation) = (column / (n_gamma - 1))^2"},
                {"unit", "cd/m^2 * sr (radiance per unit normalised phase function)"}}},
      {"rayleigh", lut_stem + ".rayleigh.exr"},
      {"mie", lut_stem + ".mie.exr"},
      {"sun_transmittance", lut_stem + ".sun_transmittance.exr"}};
  if (preset.variant == ModelVariant::kFfxvIso) luts["isotropic"] = lut_stem + ".isotropic.exr";
  json j = {{"format", kFormat}, {"format_version", kFormatVersion}, {"tool_version", kSkycalVersion},
            {"name", preset.name}, {"model", ToString(preset.variant)}, {"parameters", params}, {"luts", luts}};
  if (std::isfinite(preset.time_of_day_h)) j["time_of_day_h"] = preset.time_of_day_h;
  if (!preset.clouds_json.empty()) j["clouds"] = json::parse(preset.clouds_json);
  return j;
}

namespace {

std::vector<float> ReadLutImage(const std::string& path, int width, int height, const std::string& origin) {
  ExrRGB exr;
  try {
    exr = ReadExrRGB(path);
  } catch (const Error& e) {
    throw Error(origin + ": cannot read its LUT: " + e.what());
  }
  if (exr.image.width != width || exr.image.height != height) {
    throw Error(path + ": LUT is " + std::to_string(exr.image.width) + " x " + std::to_string(exr.image.height) +
                ", expected " + std::to_string(width) + " x " + std::to_string(height) + " (columns x rows) from " + origin);
  }
  return std::move(exr.image.pixels);
}

void WriteLutImage(const std::string& path, const std::vector<float>& data, int width, int height, const std::string& what,
                   const LutGrid& grid) {
  ImageRGB img(width, height);
  img.pixels = data;
  ExrAttributes attrs;
  attrs.strings["skycalLut"] = what;
  attrs.floats["thetaMaxDeg"] = static_cast<float>(grid.theta_max_deg);
  attrs.strings["skycalVersion"] = kSkycalVersion;
  WriteExrRGB(path, img, attrs, ExrPixelType::kFloat);
}

const json& Require(const json& j, const char* key, const std::string& origin, const std::string& prefix) {
  if (!j.is_object() || !j.contains(key)) throw Error(Field(origin, prefix + key) + " is missing");
  return j.at(key);
}

double RequireNumber(const json& j, const std::string& origin, const std::string& field) {
  if (!j.is_number()) throw Error(Field(origin, field) + ": expected a number, got " + j.dump());
  return j.get<double>();
}

}  // namespace

Preset LoadPreset(const std::string& path) {
  const json j = ReadJsonFile(path);
  if (!j.is_object() || j.value("format", "") != kFormat) {
    throw Error(Field(path, "format") + ": expected \"" + kFormat + "\" (is this a skycal preset?)");
  }
  RequireKnownKeys(j, {"format", "format_version", "tool_version", "name", "model", "time_of_day_h", "parameters", "luts",
                       "provenance", "clouds"},
                   path, "");
  RequireFormatVersion(j, kFormatVersion, path, "bake or fit it again with this skycal");
  Preset p;
  p.name = j.value("name", fs::path(path).stem().string());
  const json& model = Require(j, "model", path, "");
  if (!model.is_string()) throw Error(Field(path, "model") + ": expected a string");
  p.variant = ParseModelVariant(model.get<std::string>(), Field(path, "model"));
  if (j.contains("time_of_day_h")) {
    p.time_of_day_h = RequireNumber(j["time_of_day_h"], path, "time_of_day_h");
    if (!(p.time_of_day_h >= 0.0 && p.time_of_day_h < 24.0)) {
      throw Error(Field(path, "time_of_day_h") + ": expected hours in [0, 24)");
    }
  }
  if (j.contains("clouds")) {
    if (!j["clouds"].is_object()) throw Error(Field(path, "clouds") + ": expected an object (the cloudscape's parameters)");
    p.clouds_json = j["clouds"].dump();
  }
  const json& params = Require(j, "parameters", path, "");
  std::vector<std::string> names;
  for (const ParamSpec& s : PresetParameterSpecs()) names.push_back(s.name);
  RequireKnownKeys(params, names, path, "parameters.");
  for (const ParamSpec& s : PresetParameterSpecs()) {
    const std::string field = std::string("parameters.") + s.name + ".value";
    double* out = s.field(p);
    if (!params.contains(s.name)) {  // a silent default would hide a typo or a truncated file
      std::ostringstream def;
      def << s.default_value;
      throw Error(Field(path, std::string("parameters.") + s.name) + " is missing (a preset lists every parameter; " +
                  s.description + ", " + s.unit + ", default " + def.str() + ")");
    }
    RequireKnownKeys(params.at(s.name), {"value", "unit", "min", "max", "default", "description"}, path,
                     std::string("parameters.") + s.name + ".");
    const json& v = Require(params.at(s.name), "value", path, std::string("parameters.") + s.name + ".");
    if (s.components == 1) {
      out[0] = RequireNumber(v, path, field);
    } else {
      if (!v.is_array() || static_cast<int>(v.size()) != s.components) {
        throw Error(Field(path, field) + ": expected an array of " + std::to_string(s.components) + " numbers");
      }
      for (int c = 0; c < s.components; ++c) out[c] = RequireNumber(v[c], path, field);
    }
  }
  const json& luts = Require(j, "luts", path, "");
  RequireKnownKeys(luts, {"grid", kLutNames[0], kLutNames[1], kLutNames[2], "sun_transmittance"}, path, "luts.");
  const json& grid = Require(luts, "grid", path, "luts.");
  RequireKnownKeys(grid, {"n_theta", "n_gamma", "theta_max_deg", "row_mapping", "column_mapping", "unit"}, path, "luts.grid.");
  auto count = [&](const char* key, int max) {
    const std::string field = std::string("luts.grid.") + key;
    const double v = RequireNumber(Require(grid, key, path, "luts.grid."), path, field);
    if (!(v >= 2 && v <= max && v == std::floor(v))) {
      throw Error(Field(path, field) + ": expected an integer in [2, " + std::to_string(max) + "], got " + grid.at(key).dump());
    }
    return static_cast<int>(v);
  };
  LutGrid g;
  g.n_theta = count("n_theta", kMaxLutRows);
  g.n_gamma = count("n_gamma", kMaxLutColumns);
  g.theta_max_deg = RequireNumber(Require(grid, "theta_max_deg", path, "luts.grid."), path, "luts.grid.theta_max_deg");
  p.luts.Resize(g);
  const fs::path dir = fs::path(path).parent_path();
  auto lut_path = [&](const char* key) {
    const json& f = Require(luts, key, path, "luts.");
    if (!f.is_string()) throw Error(Field(path, std::string("luts.") + key) + ": expected a file name");
    return (dir / f.get<std::string>()).string();
  };
  const int tables = p.variant == ModelVariant::kFfxvIso ? 3 : 2;
  for (int t = 0; t < tables; ++t) {
    LutTable(p.luts, t) = ReadLutImage(lut_path(kLutNames[t]), g.n_gamma, g.n_theta, Field(path, std::string("luts.") + kLutNames[t]));
  }
  p.luts.sun_transmittance = ReadLutImage(lut_path("sun_transmittance"), 1, g.n_theta, Field(path, "luts.sun_transmittance"));
  ValidatePreset(p, path);
  return p;
}

std::vector<std::string> PresetOutputFiles(const std::string& json_path, ModelVariant variant) {
  const fs::path jp(json_path);
  const std::string stem = jp.stem().string();
  std::vector<std::string> files;
  const int tables = variant == ModelVariant::kFfxvIso ? 3 : 2;
  for (int t = 0; t < tables; ++t) files.push_back((jp.parent_path() / (stem + "." + kLutNames[t] + ".exr")).string());
  files.push_back((jp.parent_path() / (stem + ".sun_transmittance.exr")).string());
  files.push_back(json_path);  // last: a preset whose JSON exists has all its LUTs
  return files;
}

std::vector<std::string> PresetFiles(const std::string& json_path) {
  std::vector<std::string> files{json_path};
  try {
    const json j = ReadJsonFile(json_path);
    if (!j.is_object() || !j.contains("luts") || !j["luts"].is_object()) return files;
    const fs::path dir = fs::path(json_path).parent_path();
    for (const char* key : {kLutNames[0], kLutNames[1], kLutNames[2], "sun_transmittance"}) {
      const auto it = j["luts"].find(key);
      if (it != j["luts"].end() && it->is_string()) files.push_back((dir / it->get<std::string>()).string());
    }
    const auto clouds = j.find("clouds");
    if (clouds != j.end() && clouds->is_object()) {
      const auto map = clouds->find("weather_map");
      if (map != clouds->end() && map->is_string()) files.push_back((dir / map->get<std::string>()).string());
    }
  } catch (const Error&) {
    // Unreadable: LoadPreset reports it with the field; the JSON's own path is still guarded.
  }
  return files;
}

namespace {

// Test hook: SKYCAL_TEST_STOP_BETWEEN_FILES=N sends SIGTERM to this process after the N-th
// file of a preset is in place, and waits long enough for the interrupt watcher to act
// (interrupt_cleanup.h); tests prove that the preset on disk is still one whole preset.
void StopBetweenFilesForTests(size_t committed) {
  const char* env = std::getenv("SKYCAL_TEST_STOP_BETWEEN_FILES");
  if (env == nullptr || std::strtoul(env, nullptr, 10) != committed) return;
  ::kill(::getpid(), SIGTERM);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
}

}  // namespace

void SavePreset(const Preset& preset, const std::string& json_path, const json* extra) {
  ValidatePreset(preset, json_path);
  const std::vector<std::string> files = PresetOutputFiles(json_path, preset.variant);
  const std::string stem = fs::path(json_path).stem().string();
  const LutGrid& g = preset.luts.grid;
  // Every file goes to its temporary first; the renames happen together at the end, so an
  // error or interruption leaves the earlier preset (if any) whole, never a mix.
  std::vector<std::unique_ptr<AtomicOutput>> outs;
  for (const std::string& f : files) outs.push_back(std::make_unique<AtomicOutput>(f));
  const int tables = preset.variant == ModelVariant::kFfxvIso ? 3 : 2;
  for (int t = 0; t < tables; ++t) {
    WriteLutImage(outs[t]->temp_path(), LutTable(preset.luts, t), g.n_gamma, g.n_theta, kLutNames[t], g);
  }
  WriteLutImage(outs[tables]->temp_path(), preset.luts.sun_transmittance, 1, g.n_theta, "sun_transmittance", g);
  json j = PresetToJson(preset, stem);
  if (extra) {
    for (auto it = extra->begin(); it != extra->end(); ++it) j[it.key()] = it.value();
  }
  WriteJsonFileAtomically(outs.back()->temp_path(), j);
  // The renames are one unit: an interruption waits until the last (the JSON) is done, so a
  // signal never leaves new LUTs beside the old JSON (which then no longer loads).
  InterruptCleanupCriticalSection whole;
  for (size_t k = 0; k < outs.size(); ++k) {
    outs[k]->Commit();
    if (k + 1 < outs.size()) StopBetweenFilesForTests(k + 1);
  }
}

double LutOneMinusCosThetaMax(const LutGrid& g) { return 1.0 - std::cos(g.theta_max_deg * M_PI / 180.0); }

double LutRowPosition(const LutGrid& g, double sun_height) {
  return std::clamp((1.0 - sun_height) / LutOneMinusCosThetaMax(g), 0.0, 1.0) * (g.n_theta - 1);
}

double LutRowSunHeight(const LutGrid& g, int row) {
  return std::clamp(1.0 - static_cast<double>(row) / (g.n_theta - 1) * LutOneMinusCosThetaMax(g), -1.0, 1.0);
}

double LutColumnViewHeight(const LutGrid& g, int col) {
  const double u = static_cast<double>(col) / (g.n_gamma - 1);
  return std::clamp(u * u, 0.0, 1.0);
}

double LutRowSunZenithRad(const LutGrid& g, int row) { return std::acos(LutRowSunHeight(g, row)); }

double LutColumnElevationRad(const LutGrid& g, int col) { return std::asin(LutColumnViewHeight(g, col)); }

std::array<double, 3> SunTransmittance(const SkyLuts& luts, double sun_zenith_rad) {
  const LutGrid& g = luts.grid;
  const double r = LutRowPosition(g, std::cos(sun_zenith_rad));
  const int r0 = std::clamp(static_cast<int>(std::floor(r)), 0, g.n_theta - 2);
  const double f = r - r0;
  std::array<double, 3> t{};
  // Geometric interpolation where both rows are lit: transmittance is exp(-optical depth)
  // and the depth, not the transmittance, is close to linear between rows near the horizon
  // (linear interpolation over-estimated blue at 2 deg elevation by 50%).
  for (int c = 0; c < 3; ++c) {
    const double a = luts.sun_transmittance[r0 * 3 + c], b = luts.sun_transmittance[(r0 + 1) * 3 + c];
    t[c] = (a > 0.0 && b > 0.0) ? std::exp((1.0 - f) * std::log(a) + f * std::log(b)) : (1.0 - f) * a + f * b;
  }
  return t;
}

}  // namespace skycal::render
