#include "export_verb.h"

#include "report_verb.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "command_line.h"
#include "export_clouds.h"
#include "export_sun.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/preset.h"
#include "staged_directory.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;
namespace {

constexpr int kShWidth = 256, kShHeight = 128;
constexpr int kFogWidth = 64, kFogHeight = 32;

double Rec709Luminance(const render::Rgb& c) { return skycal::Rec709Luminance(c); }

// Solid-angle-weighted mean radiance of the upper hemisphere (pixel direction y > 0).
render::Rgb UpperHemisphereMean(const ImageRGB& sky) {
  render::Rgb sum{};
  double weight = 0.0;
  for (int y = 0; y < sky.height; ++y) {
    if (latlong::Latitude(y, sky.height) <= 0.0) continue;
    for (int x = 0; x < sky.width; ++x) {
      const double w = latlong::PixelSolidAngle(x, y, sky.width, sky.height);
      for (int c = 0; c < 3; ++c) {
        const double v = sky.at(x, y, c);
        if (std::isfinite(v) && v > 0.0) sum[c] += w * v;
      }
      weight += w;
    }
  }
  for (double& v : sum) v /= weight;
  return sum;
}

// Gaussian blur of a full-sphere lat-long (sigma in degrees of latitude/longitude, in pixel
// space), wrapping in longitude (period width - 1: the seam column is stored twice) and
// continuing across each pole half a turn around; then bilinear resampling at the pixel
// directions of an out_w x out_h lat-long.
ImageRGB BlurredLatLong(const ImageRGB& sky, double sigma_deg, int out_w, int out_h) {
  const int period = sky.width - 1, h = sky.height;
  const double deg_per_px = 180.0 / (h - 1);
  const double sigma_px = sigma_deg / deg_per_px;
  const int pad = static_cast<int>(std::ceil(3.0 * sigma_px));
  if (pad >= h) throw Error("--fog-sigma-deg: blur too wide for the " + std::to_string(sky.width) + "x" + std::to_string(h) + " sky");
  cv::Mat padded(h + 2 * pad, period + 2 * pad, CV_32FC3);
  const int half_turn = (period + 1) / 2;
  for (int py = 0; py < padded.rows; ++py) {
    int sy = py - pad, shift = 0;
    if (sy < 0) sy = -sy, shift = half_turn;                     // across the north pole
    if (sy > h - 1) sy = 2 * (h - 1) - sy, shift = half_turn;    // across the south pole
    for (int px = 0; px < padded.cols; ++px) {
      const int sx = (((px - pad + shift) % period) + period) % period;
      cv::Vec3f& o = padded.at<cv::Vec3f>(py, px);
      for (int c = 0; c < 3; ++c) {
        const float v = sky.at(sx, sy, c);
        o[c] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
      }
    }
  }
  cv::Mat blurred;
  cv::GaussianBlur(padded, blurred, cv::Size(2 * pad + 1, 2 * pad + 1), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  ImageRGB out(out_w, out_h);
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      const auto pos = latlong::PixelPosition(latlong::PixelDirection(x, y, out_w, out_h), sky.width, h);
      const double fx = std::clamp(pos[0], 0.0, static_cast<double>(period));
      const double fy = std::clamp(pos[1], 0.0, static_cast<double>(h - 1));
      const int x0 = std::min(static_cast<int>(fx), period - 1), y0 = std::min(static_cast<int>(fy), h - 2);
      const double ax = fx - x0, ay = fy - y0;
      for (int c = 0; c < 3; ++c) {
        auto at = [&](int xx, int yy) { return static_cast<double>(blurred.at<cv::Vec3f>(yy + pad, (xx % period) + pad)[c]); };
        const double v = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
                         ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
        out.at(x, y, c) = static_cast<float>(v);
      }
    }
  }
  return out;
}

nlohmann::json RgbJson(const render::Rgb& c) { return nlohmann::json::array({c[0], c[1], c[2]}); }

// What the export knows about a preset at its sun.
struct SunProducts {
  SunSource sun;
  double elevation_deg = 0.0;
  render::Rgb illuminance{};  // lux per channel at the ground, normal incidence
  double illuminance_lux = 0.0;
};

constexpr double kHalfMax = 65504.0;
constexpr double kHalfMinNormal = 6.103515625e-05;

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
  if (!(fog_sigma_deg > 0.0 && fog_sigma_deg <= 30.0)) {
    *why = "--fog-sigma-deg: expected degrees in (0, 30]";
    return false;
  }
  return true;
}

nlohmann::json RunExportImpl(const ExportOptions& o) {
  // Progress lines on stderr unless o.verbose is off (the bench runs the verb many times).
  const auto progress = [&o](const std::string& line) {
    if (o.verbose) Log("export", line);
  };
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  std::vector<NamedPath> inputs;
  for (const std::string& p : o.presets) {
    for (const NamedPath& f : PresetInputs("--preset", p)) inputs.push_back(f);
  }
  StagedDirectory out(o.out_dir, "--out", "export", inputs);
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
  progress("pre-exposure scale " + CsvNumber(scale) + " (largest LUT value " + CsvNumber(max_value) + " -> " +
                    CsvNumber(max_value * scale) + ", FP16 max 65504)");

  nlohmann::json manifest_presets = nlohmann::json::array();
  nlohmann::json skipped = nlohmann::json::array();
  long long underflow = 0;
  std::vector<SunProducts> suns(presets.size());
  std::unique_ptr<render::SkyRenderer> renderer;  // created on first use
  for (size_t i = 0; i < presets.size(); ++i) {
    const render::Preset& p = presets[i];
    SunProducts& sp = suns[i];
    sp.sun = SunFromProvenance(o.presets[i]);
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
    ExportPresetClouds(p, o.presets[i], out.staging(), &files);  // clouds.json + weather.exr (export_clouds.h)
    nlohmann::json sun_json, sh_json, fog_json;
    if (!sp.sun.known) {
      skipped.push_back({{"block", "sun, SH-9 and fog of preset '" + p.name + "'"},
                         {"reason", sp.sun.reason + "; exported its time-independent parts only (LUTs, parameters)"}});
    } else {
      sp.elevation_deg = latlong::ElevationDeg(sp.sun.dir);
      sp.illuminance = render::SunIlluminanceAtGround(p, sp.sun.dir);
      sp.illuminance_lux = Rec709Luminance(sp.illuminance);
      sun_json = {{"direction", RgbJson(sp.sun.dir)},
                  {"elevation_deg", sp.elevation_deg},
                  {"source", sp.sun.source},
                  {"illuminance_rgb", RgbJson(sp.illuminance)},
                  {"illuminance_lux", sp.illuminance_lux},
                  {"illuminance_note", "lux at normal incidence at the ground: sun_illuminance x sun_tint_rgb x "
                                       "SunTransmittance(sun zenith); luminance Rec.709"}};
      if (!renderer) {
        renderer = render::CreateRenderer(o.backend);
        progress("backend: " + renderer->Describe());
      }
      render::RenderRequest req;
      req.sun_dir = sp.sun.dir;
      req.width = kShWidth;
      req.height = kShHeight;
      req.sun_disc = false;
      req.ground = render::GroundMode::kLit;
      const ImageRGB sky = renderer->Render(p, req);
      const render::ShCoefficients sh = render::ProjectSh9(sky);
      nlohmann::json coeffs = nlohmann::json::array();
      for (const auto& c : sh) coeffs.push_back(RgbJson(c));
      const nlohmann::json sky_json = {{"width", kShWidth}, {"height", kShHeight}, {"sun_disc", false},
                                       {"ground", "lit"},   {"backend", render::ToString(o.backend)},
                                       {"sun_direction", RgbJson(sp.sun.dir)}};
      sh_json = {{"coefficients", coeffs},
                 {"units", "cd/m^2 per channel: L_lm = integral of L(w) Y_lm(w) dw (not pre-exposed)"},
                 {"basis_order", {"(0,0)", "(1,-1)", "(1,0)", "(1,1)", "(2,-2)", "(2,-1)", "(2,0)", "(2,1)", "(2,2)"}},
                 {"basis", "real SH, +Y up: Y00 = 1/2 sqrt(1/pi); Y1m = sqrt(3/(4pi)) {y, z, x}; Y2-2 = 1/2 sqrt(15/pi) xy, "
                           "Y2-1 = 1/2 sqrt(15/pi) yz, Y20 = 1/4 sqrt(5/pi) (3z^2 - 1), Y21 = 1/2 sqrt(15/pi) xz, "
                           "Y22 = 1/4 sqrt(15/pi) (x^2 - y^2)"},
                 {"irradiance", "E(n) = sum_lm A_l L_lm Y_lm(n), A = (pi, 2pi/3, pi/4) (Ramamoorthi-Hanrahan); the sun "
                                "disc is not included: add it as the key light"},
                 {"irradiance_band_constants", render::kShClampedCosineBand},
                 {"sky", sky_json}};
      WriteJsonFileAtomically(out / (p.name + "/sh9.json"), sh_json);
      files["sh9"] = p.name + "/sh9.json";

      const render::Rgb fog_color = UpperHemisphereMean(sky);
      ImageRGB fog = BlurredLatLong(sky, o.fog_sigma_deg, kFogWidth, kFogHeight);
      for (float& v : fog.pixels) v = static_cast<float>(v * scale);
      ExrAttributes fa;
      fa.floats["preExposure"] = static_cast<float>(scale);
      fa.floats["skycalFogSigmaDeg"] = static_cast<float>(o.fog_sigma_deg);
      fa.strings["skycalLut"] = "fog";
      fa.strings["skycalUnits"] = "cd/m^2 x preExposure";
      const std::string fog_rel = p.name + "/fog.exr";
      const ExrWriteReport frep = WriteExrRGB(out / fog_rel, fog, fa, ExrPixelType::kHalf);
      if (frep.half_overflow_count > 0) throw Error(fog_rel + ": " + std::to_string(frep.half_overflow_count) + " values overflow FP16");
      files["fog"] = fog_rel;
      fog_json = {{"color_rgb", RgbJson(fog_color)},
                  {"color_note", "solid-angle-weighted mean radiance of the upper hemisphere of the sky without the sun "
                                 "disc, cd/m^2, not pre-exposed"},
                  {"latlong", fog_rel},
                  {"latlong_size", {kFogWidth, kFogHeight}},
                  {"blur_sigma_deg", o.fog_sigma_deg},
                  {"latlong_note", "the 256x128 sky without the disc (lit ground), Gaussian-blurred in pixel space "
                                   "(longitude wraps, poles continue half a turn around), bilinearly resampled to "
                                   "64x32; half float x pre_exposure"}};
    }
    manifest_presets.push_back({{"name", p.name},
                                {"source", o.presets[i]},
                                {"sha256", Sha256OfFile(o.presets[i])},
                                {"model", render::ToString(p.variant)},
                                {"time_of_day_h", std::isfinite(p.time_of_day_h) ? nlohmann::json(p.time_of_day_h) : nlohmann::json()},
                                {"grid", {{"n_theta", g.n_theta}, {"n_gamma", g.n_gamma}, {"theta_max_deg", g.theta_max_deg}}},
                                {"files", files},
                                {"sun", sun_json},
                                {"sh9", sh_json},
                                {"fog", fog_json}});
  }

  // Keyframes over time of day.
  std::vector<const render::Preset*> keyed;
  std::map<const render::Preset*, const SunProducts*> sun_of;
  for (size_t i = 0; i < presets.size(); ++i) {
    sun_of[&presets[i]] = &suns[i];
    if (std::isfinite(presets[i].time_of_day_h)) keyed.push_back(&presets[i]);
  }
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
    size_t keyed_with_sun = 0;
    for (const render::Preset* kp : keyed) keyed_with_sun += sun_of[kp]->sun.known ? 1 : 0;
    const bool sun_columns = keyed_with_sun > 0;
    const std::vector<std::string> sun_header = {"sun_elevation_deg", "sun_illuminance_r", "sun_illuminance_g",
                                                 "sun_illuminance_b", "sun_illuminance_lux"};
    if (sun_columns) header.insert(header.end(), sun_header.begin(), sun_header.end());
    if (keyed_with_sun < keyed.size()) {
      std::string names;
      for (const render::Preset* kp : keyed)
        if (!sun_of[kp]->sun.known) names += (names.empty() ? "'" : ", '") + kp->name + "'";
      skipped.push_back({{"block", sun_columns ? "keyframe sun columns of " + names + " (left empty)"
                                               : std::string("keyframe sun columns")},
                         {"reason", "no sun direction in the provenance of " + names +
                                        " (presets written by skycal fit carry provenance.final_errors[].sun_direction)"}});
    }
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
      csv += "," + CsvNumber(scale);
      row["pre_exposure"] = scale;
      if (sun_columns) {
        const SunProducts& sp = *sun_of[kp];
        const double values[5] = {sp.elevation_deg, sp.illuminance[0], sp.illuminance[1], sp.illuminance[2],
                                  sp.illuminance_lux};
        for (size_t c = 0; c < sun_header.size(); ++c) {
          csv += "," + (sp.sun.known ? CsvNumber(values[c]) : std::string());
          row[sun_header[c]] = sp.sun.known ? nlohmann::json(values[c]) : nlohmann::json();
        }
      }
      csv += "\n";
      rows.push_back(row);
    }
    nlohmann::json units = nlohmann::json::object();
    for (const auto& spec : render::PresetParameterSpecs()) units[spec.name] = spec.unit;
    if (sun_columns) {
      units["sun_elevation_deg"] = "deg";
      units["sun_illuminance_rgb"] = "lux (at normal incidence at the ground, per channel)";
      units["sun_illuminance_lux"] = "lux (Rec.709 luminance of sun_illuminance_rgb)";
    }
    WriteFileAtomically(out / "keyframes.csv", csv);
    WriteJsonFileAtomically(out / "keyframes.json", {{"columns", header}, {"units", units}, {"keys", rows}});
  }
  ExportCloudKeyframes(presets, o.presets, out.staging(), &skipped);  // cloud_keyframes.csv/.json (export_clouds.h)
  const nlohmann::json manifest = {{"tool", std::string("skycal ") + kSkycalVersion},
                                   {"pre_exposure", scale},
                                   {"pre_exposure_note", "LUT texels = model LUT (cd/m^2 * sr) x pre_exposure; FP16"},
                                   {"half_underflow_texels", underflow},
                                   {"presets", manifest_presets},
                                   {"skipped", skipped}};
  WriteJsonFileAtomically(out / "manifest.json", manifest);
  if (o.report) WriteVerbReport("export", out.staging().string());
  out.Commit();
  for (const auto& s : skipped) progress("skipped " + s["block"].get<std::string>() + ": " + s["reason"].get<std::string>());
  progress("wrote " + o.out_dir + " (" + std::to_string(presets.size()) + " preset(s))");
  nlohmann::json summary = manifest;
  summary["out"] = o.out_dir;
  return summary;
}

ExportOptions ParseExportArgs(int argc, char** argv) {
  VerbCommandLine cl(
      "export",
      "skycal export: game tables from calibrated presets\n\n"
      "Writes GAME_DIR/manifest.json, GAME_DIR/<preset>/{rayleigh,mie[,isotropic],sun_transmittance}.exr\n"
      "(half float, multiplied by one pre-exposure scale for all presets, recorded in the manifest and\n"
      "in each EXR's `preExposure` attribute: the game divides by it, or folds it into its exposure),\n"
      "and, when the presets carry a time of day (fit --time, or the reference's skycalTimeOfDay),\n"
      "GAME_DIR/keyframes.csv and keyframes.json: one row per key sorted by time, one column per\n"
      "parameter. Presets with a clouds section (fit --clouds) add GAME_DIR/<preset>/clouds.json and\n"
      "weather.exr, and the timed ones GAME_DIR/cloud_keyframes.csv/.json: one row per time of day,\n"
      "one column per cloud lighting parameter, its unit in the header (\"extinction [1/m]\").",
      "  skycal export --preset P.json [--preset P2.json ...] --out GAME_DIR [--headroom H]\n"
      "                [--backend vulkan|cpu] [--fog-sigma-deg S] [--json]",
      "Sun-dependent outputs, for each preset whose provenance names its sun direction (fit writes\n"
      "provenance.final_errors[i].sun_direction; the first reference's is used):\n"
      "  - keyframe columns sun_elevation_deg, sun_illuminance_r/g/b (lux at normal incidence at the\n"
      "    ground: sun_illuminance x sun_tint_rgb x SunTransmittance(sun zenith)) and\n"
      "    sun_illuminance_lux (its Rec.709 luminance); empty (CSV) / null (JSON) for keys without one;\n"
      "  - the sky WITHOUT the sun disc (lit ground) rendered at 256x128 with --backend (default\n"
      "    vulkan; cpu: double reference), projected to SH-9 radiance coefficients (9 per channel,\n"
      "    basis and order of render/irradiance.h, cd/m^2, NOT pre-exposed) in the manifest and\n"
      "    GAME_DIR/<preset>/sh9.json; the game adds the sun as its key light;\n"
      "  - fog: fog_color_rgb, the solid-angle-weighted mean radiance of the upper hemisphere of that\n"
      "    sky (cd/m^2), and GAME_DIR/<preset>/fog.exr, 64x32 half float, pre-exposed like the LUTs:\n"
      "    the 256x128 sky blurred with a Gaussian of --fog-sigma-deg S degrees (default 15, at most\n"
      "    30; cv::GaussianBlur in pixel space, wrapping in longitude and continuing across the poles),\n"
      "    then bilinearly resampled at the 64x32 pixel directions.\n"
      "Presets without a sun direction keep their time-independent outputs (LUTs, parameter columns);\n"
      "what was left out is listed with its reason in the manifest's \"skipped\".");
  ExportOptions o;
  std::optional<std::string> backend;
  bool json = false;
  cl.Repeatable("--preset", &o.presets, "P.json", "calibrated preset JSON (repeat for several; required)");
  cl.Text("--out", &o.out_dir, "GAME_DIR", "output directory, written atomically (required)");
  cl.Number("--headroom", &o.headroom, "H",
            "the largest scaled LUT value is at most H x 65504 (default 0.25, two\n"
            "stops for the game's own multipliers)");
  cl.Text("--backend", &backend, "NAME", "renders the sky for SH-9 and fog: vulkan (default) or cpu (double reference)");
  cl.Number("--fog-sigma-deg", &o.fog_sigma_deg, "S", "Gaussian blur of the fog lat-long, degrees in (0, 30] (default 15)");
  bool no_report = false;
  cl.Flag("--no-report", &no_report, "do not write GAME_DIR/report.html (skycal report)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  o.report = !no_report;
  if (backend) o.backend = render::ParseBackend(*backend, "--backend");
  return o;
}

int RunExport(int argc, char** argv) {
  return RunVerb("export", WantsJson(argc, argv), [&]() { return RunExportImpl(ParseExportArgs(argc, argv)); });
}

}  // namespace skycal::cli
