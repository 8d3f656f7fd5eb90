// calibrate's per-photo pipeline and the whole run (calibrate.h).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>
#include <utility>

#include "calibrate_day.h"
#include "calibrate_figure.h"
#include "calibrate_plan.h"
#include "calibrate_weather.h"
#include "cloud_warmup.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/calibrate.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/appearance.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/export/game_export.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/render/preset.h"
#include "skycal/report/report.h"

namespace skycal::controllers {
namespace fs = std::filesystem;

void CalibrateLog(const CalibrateOptions& o, const std::string& line) {
  if (!o.verbose) return;
  if (o.log) o.log(line);
  else std::cerr << "[calibrate] " << line << "\n";
}

namespace {

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void Log(const CalibrateOptions& o, const std::string& line) { CalibrateLog(o, line); }

// A decision taken: into the plan (fit.json) and the progress log, "  what: why".
void Decide(const CalibrateOptions& o, FitPlan* plan, fit::FitDecision d) {
  Log(o, "  " + d.what + ": " + d.why);
  plan->decisions.push_back(std::move(d));
}

std::string Round(double v, double unit = 0.001) { return FormatNumber(std::round(v / unit) * unit); }

// photo.exr (the photo as the fit reads it, with its sun) and mask.exr (1 sky, 0 not, as a
// user mask; its confidence beside).
void WriteStagedInputs(const PhotoAnalysis& a, const StagedDirectory& out, const std::string& photo) {
  capture::LatLongFrame f = a.frame;
  f.sun_direction = a.sun.direction;
  f.extra.strings["skycalSunSource"] = a.sun.source;
  f.extra.strings["skycalSource"] = photo;
  capture::WriteLatLongFrame(out / "photo.exr", f);
  ImageRGB rgb(a.mask.width, a.mask.height);
  for (size_t i = 0; i < a.mask.sky.size(); ++i)
    rgb.pixels[3 * i] = rgb.pixels[3 * i + 1] = rgb.pixels[3 * i + 2] = a.mask.sky[i];
  ExrAttributes attributes;
  attributes.strings["skycalMaskSource"] = "skycal calibrate (automatic sky segmentation) of " + photo;
  WriteExrRGBWithPlanes(out / "mask.exr", rgb, {{"confidence", a.mask.confidence}}, attributes, ExrPixelType::kHalf);
}

// The cone left out of the comparison, degrees (0: none; a nominal sun draws no disc).
// `skycal compare --mask mask.exr --sun-cone` of it repeats the numbers.
double ComparedSunCone(const FitPlan& plan) { return plan.draw_sun_disc ? plan.fit.fit.sun_cone_deg : 0.0; }

// The sky pixels the game's image is judged on: the sky mask less the fit's sun cone. A
// photo's disc is clipped or lossily encoded (its radiance unmeasured), and its few pixels,
// tens of thousands of times the sky, would outweigh the rest of the sky in a log RMSE.
std::vector<float> ComparedPixels(const PhotoAnalysis& a, const FitPlan& plan) {
  if (ComparedSunCone(plan) <= 0.0) return a.mask.sky;
  return appearance::WithoutSunCone(a.mask.sky, a.frame.radiance.width, a.frame.radiance.height, *a.sun.direction,
                                    ComparedSunCone(plan));
}

struct GameJudgement {
  appearance::Comparison comparison;
  std::optional<double> cloud_iou;
  double sun_cone_deg = 0.0;  // left out of the comparison
};

// The calibrated preset rendered as the game renders it, at the photo's sun, size and
// exposure: render.exr, compare.png, and the numbers against the photo.
GameJudgement RenderTheGame(const PhotoAnalysis& a, const FitPlan& plan, const StagedDirectory& out, double exposure) {
  GameRenderOptions r;
  r.preset_path = out / "preset.json";
  r.sun_dir = *a.sun.direction;
  r.width = a.frame.radiance.width;
  r.height = a.frame.radiance.height;
  r.exposure = exposure;
  r.verbose = false;
  r.sun_disc = plan.draw_sun_disc;
  r.backend = plan.fit.fit.backend;
  r.clouds.enabled = plan.draw_clouds && !render::LoadPreset(r.preset_path).clouds_json.empty();
  const GameImage game = RenderGameImage(r);
  capture::LatLongFrame f;
  f.radiance = game.radiance;
  f.sun_direction = game.sun_dir;
  f.extra.strings["skycalRenderOf"] = "preset.json as the game renders it" + std::string(r.clouds.enabled ? ", clouds drawn" : "");
  f.extra.floats["skycalExposure"] = static_cast<float>(exposure);
  // As `skycal render --clouds` writes it: `skycal compare` then measures where the clouds sit
  // against a synthetic photo's own.
  if (!game.cloud_transmittance.empty()) f.planes.push_back({kCloudTransmittancePlane, game.cloud_transmittance});
  capture::WriteLatLongFrame(out / "render.exr", f);
  const std::vector<float> compared = ComparedPixels(a, plan);
  WriteComparisonFigure(out / "compare.png", a.frame.radiance, game.radiance, compared);
  return {appearance::Compare(a.frame.radiance, game.radiance, compared, {}, "photo.exr", "render.exr"),
          CloudIou(game.cloud_transmittance, a.cloud_probability, compared), ComparedSunCone(plan)};
}

fit::FitCalibration Record(const std::string& photo, const PhotoAnalysis& a, const GameJudgement& g) {
  const appearance::Comparison& c = g.comparison;
  fit::FitCalibration r;
  r.photo = photo;
  r.sky_kind = capture::ToString(a.kind.kind);
  r.sky_kind_reason = a.kind.reason;
  r.sky_share = a.features.sky_share;
  r.zenith_sky_share = a.features.zenith_sky_share;
  r.zenith_blue = a.features.zenith_blue;
  r.texture = a.features.texture;
  r.point_sources = a.features.point_sources;
  if (std::isfinite(a.features.cloud_share)) r.cloud_share = a.features.cloud_share;
  r.sun_source = a.sun.source;
  r.sun_uncertainty_deg = a.sun.uncertainty_deg;
  r.mask = "mask.exr";
  r.render = "render.exr";
  r.game_sky_pixels = c.sky_pixels;
  r.game_per_pixel_log_rmse = c.per_pixel_log_rmse;
  r.game_sun_cone_deg = g.sun_cone_deg;
  r.game_appearance_error = c.appearance_error;
  r.game_cloud_iou = g.cloud_iou;
  return r;
}

// The fit of the plan; when the cloud statistics find nothing to fit (a sky called partly
// cloudy whose "clouds" are not), the atmosphere alone, and a decision saying so.
void RunThePlan(const StagedDirectory& out, const CalibrateOptions& o, FitPlan* plan) {
  try {
    RunFitInto(plan->fit, out);
  } catch (const Error& e) {
    if (!plan->fit.cloud_stats.enabled) throw;
    Log(o, std::string("the cloud statistics failed (") + e.what() + "): fitting the atmosphere alone");
    plan->fit.cloud_stats.enabled = false;
    plan->fit.cloud_mask = false;
    plan->fit.previews = true;
    plan->draw_clouds = false;
    fit::FitDecision d;
    d.what = "no cloud layer: the cloud statistics found nothing to fit";
    d.why = e.what();
    d.saved_ms_basis = "not measured in this run";
    plan->decisions.push_back(d);
    RunFitInto(plan->fit, out);
  }
}

// What the exported clear sky near the horizon is, when the photo's horizon is cloudy: its
// clear pixels there are seen through the farther cloud layer (a low ray crosses kilometres
// of it inside the draw distance), so the fitted clear sky there is darker than a cloudless
// one would be (bench/results/weather_inversion.md, "The atmosphere behind the horizon's
// clouds"). Said when at least a tenth of the sky below kHorizonBandDeg is cloud in the photo.
std::optional<fit::FitDecision> HorizonSkyDecision(const PhotoAnalysis& a) {
  constexpr double kHorizonBandDeg = 20.0;
  const int w = a.frame.radiance.width, h = a.frame.radiance.height;
  if (a.cloud_probability.size() != static_cast<size_t>(w) * h) return std::nullopt;
  double sky = 0.0, cloud = 0.0;
  for (int y = 0; y < h; ++y) {
    const double el = latlong::Latitude(y, h) / kRadiansPerDegree;
    if (el <= 0.0 || el > kHorizonBandDeg) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (a.mask.sky[i] < 0.5f) continue;
      const double sa = latlong::PixelSolidAngle(x, y, w, h);
      sky += sa;
      cloud += a.cloud_probability[i] >= 0.5f ? sa : 0.0;
    }
  }
  if (!(sky > 0.0) || cloud < 0.1 * sky) return std::nullopt;
  fit::FitDecision d;
  d.what = "the clear sky below " + FormatNumber(kHorizonBandDeg) + " deg fitted between the photo's clouds";
  d.why = FormatNumber(std::round(100.0 * cloud / sky)) + "% of the sky there is cloud in the photo (cloud probability >= " +
          "0.5); the clear pixels between those clouds are seen through the farther cloud layer, so the preset's clear "
          "sky near the horizon is darker than a cloudless one: the game's image draws its clouds over it, the preset "
          "used without them would show it";
  d.saved_ms_basis = "not measured in this run";
  return d;
}

// The inverted shapes lit: the lighting refitted on them, precipitation where the photo's clouds
// are darker than that lighting draws them, the coverage read from the light texel by texel,
// and the lighting solved on from there, in one
// known-shapes fit (calibrate_weather.h). A failed refit leaves the statistics fit's lighting
// and map, and no precipitation.
void LightTheRecoveredClouds(const PhotoAnalysis& a, const PhotoWeatherView& view, const StagedDirectory& out,
                             const std::string& final_dir, const CalibrateOptions& o, FitPlan* plan) {
  Log(o, "refitting the cloud lighting on the recovered shapes, with the light inside them");
  RainFromTheLight rain(a, view, plan->fit.fit.backend);
  RefitPass pass;
  pass.refine = &rain;
  pass.start_prior = kRefitStartPrior;
  Decide(o, plan, RefitCloudLighting(*plan, out, final_dir, pass));
  if (!std::filesystem::exists(out / "fit.statistics.json")) return;  // the refit failed: nothing it found is kept
  if (auto d = HorizonSkyDecision(a)) Decide(o, plan, std::move(*d));
  Decide(o, plan, rain.Decision());
  if (!rain.refined()) return;
  fit::FitDecision d;
  d.what = "cloud lighting refitted again with the precipitation (known shapes)";
  d.why = "solved on in the same fit from the lighting above, on the map with its precipitation, for at most " +
          std::to_string(kRefitAfterRainIterations) +
          " iteration(s), no holds released; the sky and the cloud pixels kept (the precipitation moves neither); "
          "the refit's errors above are the final map's";
  d.saved_ms_basis = "not measured in this run";
  Decide(o, plan, std::move(d));
}

// Partly cloudy: the weather map inverted from the photo (or the user's, held), then the cloud
// lighting refitted on those shapes (calibrate_weather.h); each step a decision. Nothing
// without clouds.
void PlaceTheClouds(const PhotoAnalysis& a, const StagedDirectory& out, const std::string& final_dir,
                    const CalibrateOptions& o, FitPlan* plan) {
  if (!plan->draw_clouds) return;
  if (!o.weather_map.empty()) {
    plan->decisions.push_back(HoldWeatherMap(o.weather_map, out));
    Log(o, plan->decisions.back().what);
  } else if (!o.invert_weather) {
    fit::FitDecision d;
    d.what = "weather map: the statistics fit's (clouds where its noise puts them)";
    d.why = "CalibrateOptions::invert_weather is off";
    d.saved_ms_basis = "not measured in this run";
    plan->decisions.push_back(d);
    return;
  } else {
    Log(o, "inverting the weather map: the clouds where the photo has them");
    PhotoWeatherView view;
    const WeatherInversionRecord w = InvertPhotoWeather(a, out, plan->fit.fit.backend, &view);
    Decide(o, plan, w.Decision());
    if (w.done) LightTheRecoveredClouds(a, view, out, final_dir, o, plan);
    return;
  }
  Log(o, "refitting the cloud lighting on the user's shapes");
  Decide(o, plan, RefitCloudLighting(*plan, out, final_dir, {}));
}

}  // namespace

namespace {

// CalibratePhoto, `warmup` joined before the fit (null: none).
PhotoCalibration CalibrateOnePhoto(const std::string& photo, const CalibrateOptions& o, CloudDeviceWarmup* warmup) {
  const auto t0 = std::chrono::steady_clock::now();
  Log(o, "reading " + photo);
  const PhotoAnalysis a = AnalysePhoto(photo, o);
  for (const std::string& w : a.warnings) Log(o, "warning: " + w);
  Log(o, photo + ": " + capture::ToString(a.kind.kind) + " (" + a.kind.reason + "); sun " +
             (a.sun.direction ? "from " + a.sun.source + ", elevation " + Round(latlong::ElevationDeg(*a.sun.direction), 0.01) +
                                    " deg" + (a.sun.uncertainty_deg ? " +- " + Round(*a.sun.uncertainty_deg, 0.1) + " deg" : "")
                              : std::string("not placed")));
  RefuseWhatCannotBeCalibrated(photo, a);
  const std::string final_dir = (fs::path(o.out_dir) / fs::path(photo).stem()).string();
  fs::create_directories(o.out_dir);
  std::vector<NamedPath> inputs = {{"CalibrateOptions::photos", photo}};
  if (!o.weather_map.empty()) inputs.push_back({"CalibrateOptions::weather_map", o.weather_map});
  StagedDirectory out(final_dir, "CalibrateOptions::out_dir", "calibrate", inputs);
  WriteStagedInputs(a, out, photo);
  FitPlan plan = PlanFit(a, out, final_dir, o);
  for (const fit::FitDecision& d : plan.decisions) Log(o, "  " + d.what);
  Log(o, "fitting" + std::string(plan.fit.cloud_stats.enabled ? " (atmosphere, then the clouds' lighting)" : " (atmosphere)"));
  if (warmup) warmup->Join();
  RunThePlan(out, o, &plan);
  PlaceTheClouds(a, out, final_dir, o, &plan);
  fit::FitResultFile f = fit::ReadFitResultFile(out / "fit.json");
  Log(o, "rendering the calibrated preset as the game renders it" + std::string(plan.draw_clouds ? " (sky + clouds)" : ""));
  const GameJudgement c = RenderTheGame(a, plan, out, f.references.at(0).exposure);
  PhotoCalibration r;
  r.photo = photo;
  r.dir = final_dir;
  r.decisions = plan.decisions;
  r.calibration = Record(photo, a, c);
  r.seconds = Since(t0);
  r.calibration->seconds = r.seconds;
  f.decisions.insert(f.decisions.begin(), plan.decisions.begin(), plan.decisions.end());
  f.calibration = r.calibration;
  fit::WriteFitResultFile(out / "fit.json", f);
  if (o.report) {
    try {
      report::ReportOptions ro;
      ro.out_path = out / "report.html";
      ro.title = "skycal calibrate: " + photo;
      report::WriteReport(out.staging().string(), ro);
    } catch (const std::exception& e) {  // the report is optional: the calibration stands
      Log(o, "warning: " + final_dir + "/report.html not written: " + e.what());
    }
  }
  out.Commit();
  Log(o, "wrote " + final_dir + ": the game's image against the photo: per-pixel log RMSE " +
             Round(c.comparison.per_pixel_log_rmse) + ", appearance error " + Round(c.comparison.appearance_error) +
             (c.cloud_iou ? ", clouds' IoU " + Round(*c.cloud_iou) : std::string()) + " (" + Round(r.seconds, 0.1) + " s)");
  return r;
}

}  // namespace

PhotoCalibration CalibratePhoto(const std::string& photo, const CalibrateOptions& o) {
  return CalibrateOnePhoto(photo, o, nullptr);
}

int CalibrateResult::calibrated() const {
  int n = 0;
  for (const PhotoCalibration& p : photos) n += p.dir.empty() ? 0 : 1;
  return n;
}

namespace {

// The calibrated presets in DIR, this run's and earlier runs' alike: DIR/<stem>/preset.json
// beside a fit.json with a `calibration` section, in name order.
std::vector<std::string> CalibratedPresets(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const fs::path preset = e.path() / "preset.json", fit_json = e.path() / "fit.json";
    if (!e.is_directory() || e.path().filename().string().starts_with(".") || !fs::is_regular_file(preset)) continue;
    try {
      if (fs::is_regular_file(fit_json) && fit::ReadFitResultFile(fit_json.string()).calibration) out.push_back(preset.string());
    } catch (const Error&) {  // not a calibration of ours: not exported
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// DIR/game: the game tables of every calibrated preset in DIR (the export controller). A
// failure is reported, the calibrations stand.
void ExportTables(const CalibrateOptions& o, CalibrateResult* r) {
  exporter::ExportOptions e;
  e.presets = CalibratedPresets(o.out_dir);
  e.out_dir = (fs::path(o.out_dir) / "game").string();
  e.report = false;
  e.verbose = false;
  Log(o, "exporting the game tables of " + std::to_string(e.presets.size()) + " calibrated preset(s) in " + o.out_dir +
             " to " + e.out_dir);
  try {
    exporter::ExportGameTables(e);
    r->game_dir = e.out_dir;
  } catch (const std::exception& ex) {
    r->warnings.push_back(e.out_dir + " not written: " + ex.what());
    Log(o, "warning: " + r->warnings.back());
  }
}

void WriteRunReport(const CalibrateOptions& o, CalibrateResult* r) {
  report::ReportOptions ro;
  ro.out_path = (fs::path(o.out_dir) / "report.html").string();
  ro.title = "skycal calibrate: " + std::to_string(r->calibrated()) + " photo(s)";
  try {
    r->report_path = report::WriteReport(o.out_dir, ro).path;
  } catch (const std::exception& ex) {  // optional: the calibrations stand
    r->warnings.push_back(ro.out_path + " not written: " + ex.what());
    Log(o, "warning: " + r->warnings.back());
  }
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) {
    if (!s.empty()) s += ", ";
    s += n;
  }
  return s;
}

}  // namespace

CalibrateResult RunCalibrate(const CalibrateOptions& given) {
  std::vector<std::string> skipped;
  CalibrateOptions o = given;
  o.photos = ExpandPhotoFolders(given.photos, &skipped);
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (o.photos.size() != given.photos.size() || !skipped.empty())
    Log(o, std::to_string(o.photos.size()) + " photo(s), folders read in name order" +
               (skipped.empty() ? std::string("") : "; left out, not OpenEXR or Radiance pictures: " + JoinNames(skipped)));
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code kind_ec;
  const fs::file_status st = fs::symlink_status(o.out_dir, kind_ec);
  if (fs::exists(st) && !fs::is_directory(fs::status(o.out_dir, kind_ec)))
    throw Error("CalibrateOptions::out_dir = '" + o.out_dir +
                "': exists and is not a directory (expected a directory, or a path to create)");
  const bool dir_existed = fs::exists(st);
  if (!o.weather_map.empty()) clouds::LoadWeatherMap(o.weather_map, clouds::CloudParams{}.weather_extent_m);  // names the file
  const clouds::KeepCloudDevices keep;  // every stage's clouds on one pipeline: the noise uploaded once
  // While the first photo is analysed; none when no photo is a file (a refusal by name need
  // not wait for a device and a noise read it will never use).
  std::optional<CloudDeviceWarmup> warmup;
  if (std::any_of(o.photos.begin(), o.photos.end(), [](const std::string& p) {
        std::error_code ec;
        return fs::is_regular_file(p, ec);
      }))
    warmup.emplace(o.backend);
  CalibrateResult r;
  for (size_t i = 0; i < o.photos.size(); ++i) {
    Log(o, "photo " + std::to_string(i + 1) + " of " + std::to_string(o.photos.size()));
    try {
      r.photos.push_back(CalibrateOnePhoto(o.photos[i], o, warmup ? &*warmup : nullptr));
    } catch (const Error& e) {
      PhotoCalibration p;
      p.photo = o.photos[i];
      p.refusal = e.what();
      Log(o, p.refusal);
      r.photos.push_back(p);
    }
  }
  std::error_code ec;  // nothing calibrated: a DIR this run created goes again (remove only takes it empty)
  if (r.calibrated() == 0 && !dir_existed) fs::remove(o.out_dir, ec);
  if (r.calibrated() > 0) FitTheDaysWind(o, &r);  // before the tables: they carry the wind
  if (r.calibrated() > 0 && o.export_tables) ExportTables(o, &r);
  if (r.calibrated() > 0 && o.report) WriteRunReport(o, &r);
  r.seconds = Since(t0);
  return r;
}

}  // namespace skycal::controllers
