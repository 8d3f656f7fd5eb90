#include "export_verb.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include "args.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/render/preset.h"
#include "staged_directory.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;
namespace {

constexpr const char* kHelp = R"(skycal export: game tables from calibrated presets

  skycal export --preset P.json [--preset P2.json ...] --out GAME_DIR [--headroom H] [--json]

Writes GAME_DIR/manifest.json, GAME_DIR/<preset>/{rayleigh,mie[,isotropic],sun_transmittance}.exr
(half float, multiplied by one pre-exposure scale for all presets, recorded in the manifest and
in each EXR's `preExposure` attribute: the game divides by it, or folds it into its exposure),
and, when the presets carry a time of day (fit --time, or the reference's skycalTimeOfDay),
GAME_DIR/keyframes.csv and keyframes.json: one row per key sorted by time, one column per
parameter. --headroom H: the largest scaled LUT value is at most H x 65504 (default 0.25, two
stops for the game's own multipliers).
)";

constexpr double kHalfMax = 65504.0;
constexpr double kHalfMinNormal = 6.103515625e-05;

std::string CsvNumber(double v) {
  std::ostringstream ss;
  ss.precision(9);
  ss << v;
  return ss.str();
}

}  // namespace

bool ExportOptions::IsValid(std::string* why) const {
  if (presets.empty()) {
    *why = "at least one --preset is required";
    return false;
  }
  if (out_dir.empty()) {
    *why = "--out GAME_DIR is required";
    return false;
  }
  if (!(headroom > 0.0 && headroom <= 1.0)) {
    *why = "--headroom: expected a fraction in (0, 1]";
    return false;
  }
  return true;
}

nlohmann::json RunExportImpl(const ExportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  StagedDirectory out(o.out_dir, "--out", "manifest.json");
  std::vector<render::Preset> presets;
  std::map<std::string, std::string> names;  // name -> path, to refuse collisions
  for (const std::string& path : o.presets) {
    presets.push_back(render::LoadPreset(path));
    std::string& name = presets.back().name;
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..") name = fs::path(path).stem().string();
    if (!names.emplace(name, path).second) {
      throw Error(path + ": preset name '" + name + "' is also used by " + names[name] + " (each needs its own folder)");
    }
  }
  // One pre-exposure for every table: a power of two, so scaling is exact in float and half.
  double max_value = 0.0;
  for (const auto& p : presets)
    for (const auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
      for (float v : *t) max_value = std::max(max_value, static_cast<double>(v));
  const double target = o.headroom * kHalfMax;
  const double scale = max_value > 0.0 ? std::exp2(std::floor(std::log2(target / max_value))) : 1.0;
  Log("export", "pre-exposure scale " + CsvNumber(scale) + " (largest LUT value " + CsvNumber(max_value) + " -> " +
                    CsvNumber(max_value * scale) + ", FP16 max 65504)");

  nlohmann::json manifest_presets = nlohmann::json::array();
  long long underflow = 0;
  for (size_t i = 0; i < presets.size(); ++i) {
    const render::Preset& p = presets[i];
    fs::create_directories(out.staging() / p.name);
    const render::LutGrid& g = p.luts.grid;
    nlohmann::json files = nlohmann::json::object();
    const std::vector<std::pair<const char*, const std::vector<float>*>> tables = {
        {"rayleigh", &p.luts.rayleigh}, {"mie", &p.luts.mie}, {"isotropic", &p.luts.isotropic}};
    for (const auto& [name, table] : tables) {
      if (std::string(name) == "isotropic" && p.variant != render::ModelVariant::kFfxvIso) continue;
      ImageRGB img(g.n_gamma, g.n_theta);
      for (size_t k = 0; k < table->size(); ++k) {
        img.pixels[k] = static_cast<float>((*table)[k] * scale);
        if (img.pixels[k] > 0.0f && img.pixels[k] < kHalfMinNormal) ++underflow;
      }
      ExrAttributes a;
      a.floats["preExposure"] = static_cast<float>(scale);
      a.strings["skycalLut"] = name;
      a.strings["skycalUnits"] = "cd/m^2 * sr x preExposure";
      const std::string rel = p.name + "/" + name + ".exr";
      const ExrWriteReport rep = WriteExrRGB(out / rel, img, a, ExrPixelType::kHalf);
      if (rep.half_overflow_count > 0) throw Error(rel + ": " + std::to_string(rep.half_overflow_count) + " values overflow FP16");
      files[name] = rel;
    }
    ImageRGB tr(1, g.n_theta);
    for (size_t k = 0; k < p.luts.sun_transmittance.size(); ++k) tr.pixels[k] = p.luts.sun_transmittance[k];
    ExrAttributes ta;
    ta.strings["skycalLut"] = "sun_transmittance";
    WriteExrRGB(out / (p.name + "/sun_transmittance.exr"), tr, ta, ExrPixelType::kHalf);
    files["sun_transmittance"] = p.name + "/sun_transmittance.exr";
    manifest_presets.push_back({{"name", p.name},
                                {"source", o.presets[i]},
                                {"sha256", Sha256OfFile(o.presets[i])},
                                {"model", render::ToString(p.variant)},
                                {"time_of_day_h", std::isfinite(p.time_of_day_h) ? nlohmann::json(p.time_of_day_h) : nlohmann::json()},
                                {"grid", {{"n_theta", g.n_theta}, {"n_gamma", g.n_gamma}, {"theta_max_deg", g.theta_max_deg}}},
                                {"files", files}});
  }

  // Keyframes over time of day.
  nlohmann::json skipped = nlohmann::json::array();
  std::vector<const render::Preset*> keyed;
  for (const auto& p : presets)
    if (std::isfinite(p.time_of_day_h)) keyed.push_back(&p);
  if (keyed.empty()) {
    skipped.push_back({{"block", "keyframe table"}, {"reason", "no preset carries time_of_day_h (fit --time H)"}});
  } else {
    if (keyed.size() < presets.size()) {
      skipped.push_back({{"block", "keyframes of untimed presets"},
                         {"reason", std::to_string(presets.size() - keyed.size()) + " preset(s) without time_of_day_h"}});
    }
    std::sort(keyed.begin(), keyed.end(), [](auto* a, auto* b) { return a->time_of_day_h < b->time_of_day_h; });
    for (size_t k = 1; k < keyed.size(); ++k) {
      if (keyed[k]->time_of_day_h == keyed[k - 1]->time_of_day_h) {
        throw Error("presets '" + keyed[k - 1]->name + "' and '" + keyed[k]->name + "' have the same time_of_day_h " +
                    CsvNumber(keyed[k]->time_of_day_h) + " (one key per time)");
      }
    }
    std::vector<std::string> header = {"time_of_day_h", "preset"};
    for (const auto& spec : render::PresetParameterSpecs()) {
      if (spec.components == 1) {
        header.push_back(spec.name);
      } else {
        for (const char* c : {"_r", "_g", "_b"}) header.push_back(std::string(spec.name) + c);
      }
    }
    header.push_back("pre_exposure");
    std::string csv;
    for (size_t k = 0; k < header.size(); ++k) csv += (k ? "," : "") + header[k];
    csv += "\n";
    nlohmann::json rows = nlohmann::json::array();
    for (const render::Preset* kp : keyed) {
      render::Preset p = *kp;
      nlohmann::json row = {{"time_of_day_h", p.time_of_day_h}, {"preset", p.name}};
      csv += CsvNumber(p.time_of_day_h) + "," + p.name;
      for (const auto& spec : render::PresetParameterSpecs()) {
        const double* v = spec.field(p);
        for (int c = 0; c < spec.components; ++c) {
          csv += "," + CsvNumber(v[c]);
          row[spec.components == 1 ? std::string(spec.name) : std::string(spec.name) + (c == 0 ? "_r" : c == 1 ? "_g" : "_b")] = v[c];
        }
      }
      csv += "," + CsvNumber(scale) + "\n";
      row["pre_exposure"] = scale;
      rows.push_back(row);
    }
    nlohmann::json units = nlohmann::json::object();
    for (const auto& spec : render::PresetParameterSpecs()) units[spec.name] = spec.unit;
    WriteFileAtomically(out / "keyframes.csv", csv);
    WriteJsonFileAtomically(out / "keyframes.json", {{"columns", header}, {"units", units}, {"keys", rows}});
  }
  const nlohmann::json manifest = {{"tool", std::string("skycal ") + kSkycalVersion},
                                   {"pre_exposure", scale},
                                   {"pre_exposure_note", "LUT texels = model LUT (cd/m^2 * sr) x pre_exposure; FP16"},
                                   {"half_underflow_texels", underflow},
                                   {"presets", manifest_presets},
                                   {"skipped", skipped}};
  WriteJsonFileAtomically(out / "manifest.json", manifest);
  out.Commit();
  for (const auto& s : skipped) Log("export", "skipped " + s["block"].get<std::string>() + ": " + s["reason"].get<std::string>());
  Log("export", "wrote " + o.out_dir + " (" + std::to_string(presets.size()) + " preset(s))");
  nlohmann::json summary = manifest;
  summary["out"] = o.out_dir;
  return summary;
}

int RunExport(int argc, char** argv) {
  if (WantsHelp(argc, argv)) {
    std::cout << kHelp;
    return 0;
  }
  return RunVerb("export", WantsJson(argc, argv), [&]() {
    Args a(argc, argv, {"preset", "out", "headroom"}, {"json"});
    ExportOptions o;
    o.presets = a.Values("preset");
    o.out_dir = a.Value("out").value_or("");
    if (auto h = a.Number("headroom")) o.headroom = *h;
    return RunExportImpl(o);
  });
}

}  // namespace skycal::cli
