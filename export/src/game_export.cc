#include "skycal/export/game_export.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/sha256.h"
#include "skycal/core/staged_directory.h"
#include "skycal/core/version.h"
#include "skycal/export/export_clouds.h"
#include "skycal/export/export_sun.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/preset.h"
#include "skycal/report/report.h"

namespace skycal::exporter {
namespace fs = std::filesystem;
namespace {

void Log(const std::string& message) { std::cerr << "[export] " << message << std::endl; }

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
  if (pad >= h)
    throw Error("ExportOptions::fog_sigma_deg = " + FormatNumber(sigma_deg) + ": blur too wide for the " +
                std::to_string(sky.width) + "x" + std::to_string(h) + " sky");
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
    *why = "ExportOptions::presets is empty (expected at least one preset JSON)";
    return false;
  }
  if (out_dir.empty()) {
    *why = "ExportOptions::out_dir is required (the game directory)";
    return false;
  }
  if (!(headroom > 0.0 && headroom <= 1.0)) {
    *why = "ExportOptions::headroom = " + FormatNumber(headroom) + " (expected a fraction in (0, 1])";
    return false;
  }
  if (!(fog_sigma_deg > 0.0 && fog_sigma_deg <= 30.0)) {
    *why = "ExportOptions::fog_sigma_deg = " + FormatNumber(fog_sigma_deg) + " (expected degrees in (0, 30])";
    return false;
  }
  return true;
}

namespace {

// Progress lines on stderr unless options.verbose is off (the bench runs the export many times).
void Progress(const ExportOptions& o, const std::string& line) {
  if (o.verbose) Log(line);
}

// The presets, each named for its folder (its file's stem where its name cannot be one);
// two presets of one name are refused.
std::vector<render::Preset> LoadNamedPresets(const std::vector<std::string>& paths) {
  std::vector<render::Preset> presets;
  std::map<std::string, std::string> names;  // name -> path, to refuse collisions
  for (const std::string& path : paths) {
    presets.push_back(render::LoadPreset(path));
    std::string& name = presets.back().name;
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..") name = fs::path(path).stem().string();
    if (!names.emplace(name, path).second) {
      throw Error(path + ": preset name '" + name + "' is also used by " + names[name] + " (each needs its own folder)");
    }
  }
  return presets;
}

// One pre-exposure for every table: a power of two, so scaling is exact in float and half.
double PreExposureScale(const ExportOptions& o, const std::vector<render::Preset>& presets) {
  double max_value = 0.0;
  for (const auto& p : presets)
    for (const auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
      for (float v : *t) max_value = std::max(max_value, static_cast<double>(v));
  const double target = o.headroom * kHalfMax;
  const double scale = max_value > 0.0 ? std::exp2(std::floor(std::log2(target / max_value))) : 1.0;
  Progress(o, "pre-exposure scale " + CsvNumber(scale) + " (largest LUT value " + CsvNumber(max_value) + " -> " +
                  CsvNumber(max_value * scale) + ", FP16 max 65504)");
  return scale;
}

// The preset's LUTs as half-float EXRs, pre-exposed (sun transmittance as it is); counts
// the texels that fall below FP16's smallest normal into `underflow`.
void ExportPresetLuts(const render::Preset& p, double scale, const StagedDirectory& out, nlohmann::json* files,
                      long long* underflow) {
  const render::LutGrid& g = p.luts.grid;
  const std::vector<std::pair<const char*, const std::vector<float>*>> tables = {
      {"rayleigh", &p.luts.rayleigh}, {"mie", &p.luts.mie}, {"isotropic", &p.luts.isotropic}};
  for (const auto& [name, table] : tables) {
    if (std::string(name) == "isotropic" && p.variant != render::ModelVariant::kFfxvIso) continue;
    ImageRGB img(g.n_gamma, g.n_theta);
    for (size_t k = 0; k < table->size(); ++k) {
      img.pixels[k] = static_cast<float>((*table)[k] * scale);
      if (img.pixels[k] > 0.0f && img.pixels[k] < kHalfMinNormal) ++*underflow;
    }
    ExrAttributes a;
    a.floats["preExposure"] = static_cast<float>(scale);
    a.strings["skycalLut"] = name;
    a.strings["skycalUnits"] = "cd/m^2 * sr x preExposure";
    const std::string rel = p.name + "/" + name + ".exr";
    const ExrWriteReport rep = WriteExrRGB(out / rel, img, a, ExrPixelType::kHalf);
    if (rep.half_overflow_count > 0) throw Error(rel + ": " + std::to_string(rep.half_overflow_count) + " values overflow FP16");
    (*files)[name] = rel;
  }
  ImageRGB tr(1, g.n_theta);
  for (size_t k = 0; k < p.luts.sun_transmittance.size(); ++k) tr.pixels[k] = p.luts.sun_transmittance[k];
  ExrAttributes ta;
  ta.strings["skycalLut"] = "sun_transmittance";
  WriteExrRGB(out / (p.name + "/sun_transmittance.exr"), tr, ta, ExrPixelType::kHalf);
  (*files)["sun_transmittance"] = p.name + "/sun_transmittance.exr";
}

// The sky's SH-9 radiance coefficients and how they were found (sh9.json's content).
nlohmann::json Sh9Json(const ImageRGB& sky, render::Backend backend, const render::Dir3& sun_dir) {
  const render::ShCoefficients sh = render::ProjectSh9(sky);
  nlohmann::json coeffs = nlohmann::json::array();
  for (const auto& c : sh) coeffs.push_back(RgbJson(c));
  const nlohmann::json sky_json = {{"width", kShWidth}, {"height", kShHeight}, {"sun_disc", false},
                                   {"ground", "lit"},   {"backend", render::ToString(backend)},
                                   {"sun_direction", RgbJson(sun_dir)}};
  return {{"coefficients", coeffs},
          {"units", "cd/m^2 per channel: L_lm = integral of L(w) Y_lm(w) dw (not pre-exposed)"},
          {"basis_order", {"(0,0)", "(1,-1)", "(1,0)", "(1,1)", "(2,-2)", "(2,-1)", "(2,0)", "(2,1)", "(2,2)"}},
          {"basis", "real SH, +Y up: Y00 = 1/2 sqrt(1/pi); Y1m = sqrt(3/(4pi)) {y, z, x}; Y2-2 = 1/2 sqrt(15/pi) xy, "
                    "Y2-1 = 1/2 sqrt(15/pi) yz, Y20 = 1/4 sqrt(5/pi) (3z^2 - 1), Y21 = 1/2 sqrt(15/pi) xz, "
                    "Y22 = 1/4 sqrt(15/pi) (x^2 - y^2)"},
          {"irradiance", "E(n) = sum_lm A_l L_lm Y_lm(n), A = (pi, 2pi/3, pi/4) (Ramamoorthi-Hanrahan); the sun "
                         "disc is not included: add it as the key light"},
          {"irradiance_band_constants", render::kShClampedCosineBand},
          {"sky", sky_json}};
}

// The fog of the sky at the preset's sun: its colour (upper-hemisphere mean) and the
// blurred, pre-exposed lat-long written to <preset>/fog.exr. Returns the manifest's fog block.
nlohmann::json ExportFog(const ExportOptions& o, const render::Preset& p, const ImageRGB& sky, double scale,
                         const StagedDirectory& out, nlohmann::json* files) {
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
  (*files)["fog"] = fog_rel;
  return {{"color_rgb", RgbJson(fog_color)},
          {"color_note", "solid-angle-weighted mean radiance of the upper hemisphere of the sky without the sun "
                         "disc, cd/m^2, not pre-exposed"},
          {"latlong", fog_rel},
          {"latlong_size", {kFogWidth, kFogHeight}},
          {"blur_sigma_deg", o.fog_sigma_deg},
          {"latlong_note", "the 256x128 sky without the disc (lit ground), Gaussian-blurred in pixel space "
                           "(longitude wraps, poles continue half a turn around), bilinearly resampled to "
                           "64x32; half float x pre_exposure"}};
}

// The sun-dependent outputs of one preset whose sun is known: its illuminance at the
// ground, SH-9 (sh9.json) and fog; the sky is rendered once for both.
struct SunBlocks {
  nlohmann::json sun, sh9, fog;
};

SunBlocks ExportSunProducts(const ExportOptions& o, const render::Preset& p, double scale, const StagedDirectory& out,
                            std::unique_ptr<render::SkyRenderer>* renderer, SunProducts* sp, nlohmann::json* files) {
  sp->elevation_deg = latlong::ElevationDeg(sp->sun.dir);
  sp->illuminance = render::SunIlluminanceAtGround(p, sp->sun.dir);
  sp->illuminance_lux = Rec709Luminance(sp->illuminance);
  SunBlocks b;
  b.sun = {{"direction", RgbJson(sp->sun.dir)},
           {"elevation_deg", sp->elevation_deg},
           {"source", sp->sun.source},
           {"illuminance_rgb", RgbJson(sp->illuminance)},
           {"illuminance_lux", sp->illuminance_lux},
           {"illuminance_note", "lux at normal incidence at the ground: sun_illuminance x sun_tint_rgb x "
                                "SunTransmittance(sun zenith); luminance Rec.709"}};
  if (!*renderer) {
    *renderer = render::CreateRenderer(o.backend);
    Progress(o, "backend: " + (*renderer)->Describe());
  }
  render::RenderRequest req;
  req.sun_dir = sp->sun.dir;
  req.width = kShWidth;
  req.height = kShHeight;
  req.sun_disc = false;
  req.ground = render::GroundMode::kLit;
  const ImageRGB sky = (*renderer)->Render(p, req);
  b.sh9 = Sh9Json(sky, o.backend, sp->sun.dir);
  WriteJsonFileAtomically(out / (p.name + "/sh9.json"), b.sh9);
  (*files)["sh9"] = p.name + "/sh9.json";
  b.fog = ExportFog(o, p, sky, scale, out, files);
  return b;
}

// Every output of one preset (LUTs, clouds, and at a known sun its sun, SH-9 and fog);
// returns its manifest entry.
nlohmann::json ExportPreset(const ExportOptions& o, const render::Preset& p, const std::string& path, double scale,
                            const StagedDirectory& out, std::unique_ptr<render::SkyRenderer>* renderer,
                            SunProducts* sp, long long* underflow, nlohmann::json* skipped) {
  sp->sun = SunFromProvenance(path);
  fs::create_directories(out.staging() / p.name);
  nlohmann::json files = nlohmann::json::object();
  ExportPresetLuts(p, scale, out, &files, underflow);
  ExportPresetClouds(p, path, out.staging(), &files);  // clouds.json + weather.exr (export_clouds.h)
  SunBlocks b;
  if (!sp->sun.known) {
    skipped->push_back({{"block", "sun, SH-9 and fog of preset '" + p.name + "'"},
                        {"reason", sp->sun.reason + "; exported its time-independent parts only (LUTs, parameters)"}});
  } else {
    b = ExportSunProducts(o, p, scale, out, renderer, sp, &files);
  }
  const render::LutGrid& g = p.luts.grid;
  return {{"name", p.name},
          {"source", path},
          {"sha256", Sha256OfFile(path)},
          {"model", render::ToString(p.variant)},
          {"time_of_day_h", std::isfinite(p.time_of_day_h) ? nlohmann::json(p.time_of_day_h) : nlohmann::json()},
          {"grid", {{"n_theta", g.n_theta}, {"n_gamma", g.n_gamma}, {"theta_max_deg", g.theta_max_deg}}},
          {"files", files},
          {"sun", b.sun},
          {"sh9", b.sh9},
          {"fog", b.fog}};
}

const std::vector<std::string>& SunHeader() {
  static const std::vector<std::string> h = {"sun_elevation_deg", "sun_illuminance_r", "sun_illuminance_g",
                                             "sun_illuminance_b", "sun_illuminance_lux"};
  return h;
}

// The keyframe table's columns: time, preset, every parameter component, the pre-exposure,
// and the sun's columns when any key has a sun.
std::vector<std::string> KeyframeHeader(bool sun_columns) {
  std::vector<std::string> header = {"time_of_day_h", "preset"};
  for (const auto& spec : render::PresetParameterSpecs()) {
    if (spec.components == 1) {
      header.push_back(spec.name);
    } else {
      for (const char* c : {"_r", "_g", "_b"}) header.push_back(std::string(spec.name) + c);
    }
  }
  header.push_back("pre_exposure");
  if (sun_columns) header.insert(header.end(), SunHeader().begin(), SunHeader().end());
  return header;
}

// One key: its CSV line (appended to `csv`) and its JSON row.
nlohmann::json KeyframeRow(const render::Preset& key, const SunProducts& sp, double scale, bool sun_columns,
                           std::string* csv) {
  render::Preset p = key;  // PresetParameterSpecs' field() takes a mutable preset
  nlohmann::json row = {{"time_of_day_h", p.time_of_day_h}, {"preset", p.name}};
  *csv += CsvNumber(p.time_of_day_h) + "," + p.name;
  for (const auto& spec : render::PresetParameterSpecs()) {
    const double* v = spec.field(p);
    for (int c = 0; c < spec.components; ++c) {
      *csv += "," + CsvNumber(v[c]);
      row[spec.components == 1 ? std::string(spec.name) : std::string(spec.name) + (c == 0 ? "_r" : c == 1 ? "_g" : "_b")] = v[c];
    }
  }
  *csv += "," + CsvNumber(scale);
  row["pre_exposure"] = scale;
  if (sun_columns) {
    const double values[5] = {sp.elevation_deg, sp.illuminance[0], sp.illuminance[1], sp.illuminance[2],
                              sp.illuminance_lux};
    for (size_t c = 0; c < SunHeader().size(); ++c) {
      *csv += "," + (sp.sun.known ? CsvNumber(values[c]) : std::string());
      row[SunHeader()[c]] = sp.sun.known ? nlohmann::json(values[c]) : nlohmann::json();
    }
  }
  *csv += "\n";
  return row;
}

// The timed presets sorted by time (two keys at one time are refused); untimed ones are
// listed in `skipped`.
std::vector<size_t> KeyedPresets(const std::vector<render::Preset>& presets, nlohmann::json* skipped) {
  std::vector<size_t> keyed;
  for (size_t i = 0; i < presets.size(); ++i)
    if (std::isfinite(presets[i].time_of_day_h)) keyed.push_back(i);
  if (keyed.empty()) {
    skipped->push_back({{"block", "keyframe table"}, {"reason", "no preset carries time_of_day_h (a fit given the time of day records it)"}});
    return keyed;
  }
  if (keyed.size() < presets.size()) {
    skipped->push_back({{"block", "keyframes of untimed presets"},
                        {"reason", std::to_string(presets.size() - keyed.size()) + " preset(s) without time_of_day_h"}});
  }
  std::sort(keyed.begin(), keyed.end(),
            [&](size_t a, size_t b) { return presets[a].time_of_day_h < presets[b].time_of_day_h; });
  for (size_t k = 1; k < keyed.size(); ++k) {
    const render::Preset &a = presets[keyed[k - 1]], &b = presets[keyed[k]];
    if (b.time_of_day_h == a.time_of_day_h) {
      throw Error("presets '" + a.name + "' and '" + b.name + "' have the same time_of_day_h " +
                  CsvNumber(b.time_of_day_h) + " (one key per time)");
    }
  }
  return keyed;
}

// keyframes.csv and keyframes.json: one row per timed preset, sorted by time, one column
// per parameter (and the sun's where known).
void ExportKeyframes(const std::vector<render::Preset>& presets, const std::vector<SunProducts>& suns, double scale,
                     const StagedDirectory& out, nlohmann::json* skipped) {
  const std::vector<size_t> keyed = KeyedPresets(presets, skipped);
  if (keyed.empty()) return;
  size_t keyed_with_sun = 0;
  for (size_t i : keyed) keyed_with_sun += suns[i].sun.known ? 1 : 0;
  const bool sun_columns = keyed_with_sun > 0;
  const std::vector<std::string> header = KeyframeHeader(sun_columns);
  if (keyed_with_sun < keyed.size()) {
    std::string names;
    for (size_t i : keyed)
      if (!suns[i].sun.known) names += (names.empty() ? "'" : ", '") + presets[i].name + "'";
    skipped->push_back({{"block", sun_columns ? "keyframe sun columns of " + names + " (left empty)"
                                              : std::string("keyframe sun columns")},
                        {"reason", "no sun direction in the provenance of " + names +
                                       " (presets written by skycal fit carry provenance.final_errors[].sun_direction)"}});
  }
  std::string csv;
  for (size_t k = 0; k < header.size(); ++k) csv += (k ? "," : "") + header[k];
  csv += "\n";
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i : keyed) rows.push_back(KeyframeRow(presets[i], suns[i], scale, sun_columns, &csv));
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

// STAGING/report.html (skycal_report) over the export's own output.
void WriteExportReport(const std::string& staging_dir) {
  report::ReportOptions ro;
  ro.max_depth = 0;
  report::ReportSummary s;
  try {
    s = report::WriteReport(staging_dir, ro);
  } catch (const Error& e) {
    throw Error(std::string("report.html: ") + e.what() + " (ExportOptions::report = false leaves the report out)");
  }
  Log("report.html: " + std::to_string(s.images) + " images, " + std::to_string(s.plots) + " plots, " +
      std::to_string(s.bytes / 1024) + " KiB");
}

}  // namespace

nlohmann::json ExportGameTables(const ExportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  std::vector<NamedPath> inputs;
  for (const std::string& p : o.presets) {
    const std::vector<std::string> files = render::PresetFiles(p);  // the JSON, then every LUT EXR it names
    for (size_t i = 0; i < files.size(); ++i)
      inputs.push_back({i == 0 ? std::string("ExportOptions::presets") : "ExportOptions::presets " + p + "'s LUT", files[i]});
  }
  StagedDirectory out(o.out_dir, "ExportOptions::out_dir", "export", inputs);
  const std::vector<render::Preset> presets = LoadNamedPresets(o.presets);
  const double scale = PreExposureScale(o, presets);
  nlohmann::json manifest_presets = nlohmann::json::array(), skipped = nlohmann::json::array();
  long long underflow = 0;
  std::vector<SunProducts> suns(presets.size());
  std::unique_ptr<render::SkyRenderer> renderer;  // created on first use
  for (size_t i = 0; i < presets.size(); ++i)
    manifest_presets.push_back(ExportPreset(o, presets[i], o.presets[i], scale, out, &renderer, &suns[i], &underflow, &skipped));
  ExportKeyframes(presets, suns, scale, out, &skipped);
  ExportCloudKeyframes(presets, o.presets, out.staging(), &skipped);  // cloud_keyframes.csv/.json (export_clouds.h)
  const nlohmann::json manifest = {{"tool", std::string("skycal ") + kSkycalVersion},
                                   {"pre_exposure", scale},
                                   {"pre_exposure_note", "LUT texels = model LUT (cd/m^2 * sr) x pre_exposure; FP16"},
                                   {"half_underflow_texels", underflow},
                                   {"presets", manifest_presets},
                                   {"skipped", skipped}};
  WriteJsonFileAtomically(out / "manifest.json", manifest);
  if (o.report) WriteExportReport(out.staging().string());
  out.Commit();
  for (const auto& s : skipped) Progress(o, "skipped " + s["block"].get<std::string>() + ": " + s["reason"].get<std::string>());
  Progress(o, "wrote " + o.out_dir + " (" + std::to_string(presets.size()) + " preset(s))");
  nlohmann::json summary = manifest;
  summary["out"] = o.out_dir;
  return summary;
}

}  // namespace skycal::exporter
