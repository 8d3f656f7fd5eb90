#include "skycal/controllers/game_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>

#include "skycal/capture/latlong_frame.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/clouds/composite.h"
#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/atomic_output_group.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/finite_pixels.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/output_kind.h"
#include "skycal/render/renderer_stats.h"

namespace skycal::controllers {
namespace {

using Clock = std::chrono::steady_clock;

bool Fail(std::string* why, const std::string& text) {
  if (why) *why = text;
  return false;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

// A progress line or warning: to the caller's log, else stderr as the verb always printed it.
void Say(const GameRenderOptions& o, const std::string& line) {
  if (o.log) {
    o.log(line);
  } else {
    std::cerr << "[render] " << line << std::endl;
  }
}

// The sun and the image size. The messages keep the shape the render verb's have always had
// ("FIELD: reason" or "FIELD = VALUE: reason"), so that the verb, writing its flags for the
// fields, prints what it printed before these checks moved here.
bool ValidFrame(const GameRenderOptions& o, std::string* why) {
  const auto& d = o.sun_dir;
  const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(std::abs(n - 1.0) <= 1e-6))
    return Fail(why, "GameRenderOptions::sun_dir = (" + FormatNumber(d[0]) + ", " + FormatNumber(d[1]) + ", " +
                         FormatNumber(d[2]) + ") (expected a finite unit vector toward the sun)");
  render::RenderRequest r;
  r.width = o.width;
  r.height = o.height;
  std::string reason;
  if (!r.IsValid(&reason)) return Fail(why, "GameRenderOptions::width x height: " + reason);
  if (o.width != 2 * o.height)  // the project's lat-long convention; fit and import read 2:1 only
    return Fail(why, "GameRenderOptions::width x height = " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                         ": expected a 2:1 lat-long (width = 2 x height), as fit and import read");
  return true;
}

bool ValidClouds(const GameCloudOptions& c, std::string* why) {
  if (!c.enabled) return true;
  if (!(std::abs(c.time_s) <= 1.0e7)) return Fail(why, "GameCloudOptions::time_s: expected seconds within [-1e7, 1e7]");
  std::string reason;
  if (!c.march.IsValid(&reason)) return Fail(why, "GameCloudOptions::march." + reason);
  return true;
}

bool ValidExposure(double exposure, std::string* why) {
  if (std::isfinite(exposure) && exposure > 0.0) return true;
  return Fail(why, "GameRenderOptions::exposure = " + FormatNumber(exposure) + " (expected a finite scale > 0)");
}

}  // namespace

std::string DefaultPresetPath() { return DataPath("datasets/presets/default_clear.json"); }

bool GameRenderOptions::IsValid(std::string* why) const {
  return ValidFrame(*this, why) && ValidClouds(clouds, why) && ValidExposure(exposure, why);
}

// The order of the checks is the render verb's, which has printed the first failure since
// before they moved here.
bool GameRenderFileOptions::IsValid(std::string* why) const {
  if (!ValidFrame(render, why)) return false;
  if (time_of_day_h && !(*time_of_day_h >= 0.0 && *time_of_day_h < 24.0))
    return Fail(why, "GameRenderFileOptions::time_of_day_h: expected hours in [0, 24)");
  if (out_exr.empty() || !EndsWith(out_exr, ".exr"))
    return Fail(why, "GameRenderFileOptions::out_exr: expected an output path ending in .exr");
  if (!out_png.empty() && !EndsWith(out_png, ".png"))
    return Fail(why, "GameRenderFileOptions::out_png: expected a path ending in .png");
  if (!ValidClouds(render.clouds, why)) return false;
  if (!std::isnan(png_exposure_ev) && std::abs(png_exposure_ev) > 64)
    return Fail(why, "GameRenderFileOptions::png_exposure_ev: expected stops in [-64, 64]");
  return ValidExposure(render.exposure, why);
}

namespace {

// The clouds over the sky in `image` (disc included: the clouds' transmittance hides it);
// returns the summary's `clouds` object.
nlohmann::json RenderCloudsOver(const GameRenderOptions& o, const render::Preset& preset, const CloudInputsLoaded& in,
                                clouds::CloudRenderer& cloud_renderer, GameImage* image) {
  clouds::CloudRenderRequest cr;
  cr.sun_dir = image->sun_dir;
  cr.width = o.width;
  cr.height = o.height;
  cr.time_s = o.clouds.time_s;
  cr.march = o.clouds.march;
  const clouds::CloudScene scene{&preset, &in.params, in.noise.get(), &in.weather};
  clouds::CloudImage cloud = cloud_renderer.Render(scene, cr);
  image->radiance = clouds::CompositeClouds(image->radiance, cloud);
  image->clouds_drawn = true;
  image->clouds_origin = in.params_origin;
  image->weather_map_origin = in.weather_origin;
  double t_mean = 0.0;
  for (float t : cloud.transmittance) t_mean += t / cloud.transmittance.size();
  image->cloud_transmittance = std::move(cloud.transmittance);
  return {{"device", cloud_renderer.Describe()},
          {"parameters", in.params_origin},
          {"weather_map", in.weather_origin},
          {"time_s", o.clouds.time_s},
          {"transmittance_mean", t_mean},
          {"steps", {o.clouds.march.steps_zenith, o.clouds.march.steps_horizon}},
          {"light_samples", o.clouds.march.light_samples}};
}

nlohmann::json SunBelowLutWarnings(const GameRenderOptions& o, const render::Preset& preset, double elevation) {
  nlohmann::json warnings = nlohmann::json::array();
  const double lut_min_elevation = 90.0 - preset.luts.grid.theta_max_deg;
  if (elevation < lut_min_elevation) {
    warnings.push_back("sun elevation " + std::to_string(elevation) + " deg is below the LUT's range (" +
                       std::to_string(lut_min_elevation) + " deg): the last twilight row is used");
  }
  for (const auto& w : warnings) Say(o, "warning: " + w.get<std::string>());
  return warnings;
}

// The cloud pipeline is created (lavapipe compiles the shader) before the render clock starts.
std::unique_ptr<clouds::CloudRenderer> CreateCloudRenderer(const GameRenderOptions& o) {
  if (o.backend == render::Backend::kVulkan) return clouds::CreateVulkanCloudRenderer(o.vulkan_validation);
  return clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
}

nlohmann::json OrNull(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

// time_ms.gpu: each pass's device time by timestamp queries (null for the CPU backend, a
// pass not drawn, or a device without timestamps: then a warning says so).
nlohmann::json GpuTimes(const GameRenderOptions& o, const render::SkyRenderer& sky, const clouds::CloudRenderer* cloud,
                        nlohmann::json* warnings) {
  const DeviceStats s = render::RendererDeviceStats(sky);
  nlohmann::json j = {{"sky", OrNull(s.gpu_ms)}, {"clouds", nullptr}};
  if (cloud) j["clouds"] = OrNull(clouds::RendererDeviceStats(*cloud).gpu_ms);
  if (o.backend == render::Backend::kVulkan && !s.gpu_ms) {
    const std::string w = "the Vulkan device's queue reports no timestamp support: time_ms.gpu is null";
    warnings->push_back(w);
    Say(o, "warning: " + w);
  }
  return j;
}

void ApplyExposure(double exposure, ImageRGB* radiance) {
  if (exposure == 1.0) return;
  for (float& v : radiance->pixels) v = static_cast<float>(v * exposure);
}

}  // namespace

GameImage RenderGameImage(const GameRenderOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  GameImage g;
  g.preset_path = o.preset_path.empty() ? DefaultPresetPath() : o.preset_path;
  const render::Preset preset = render::LoadPreset(g.preset_path);
  std::optional<CloudInputsLoaded> cloud_inputs;
  if (o.clouds.enabled) cloud_inputs = LoadCloudInputs(o.clouds, preset, g.preset_path);  // before any time is spent
  g.sun_dir = o.sun_dir;
  const double elevation = latlong::ElevationDeg(g.sun_dir), azimuth = latlong::AzimuthDeg(g.sun_dir);
  const nlohmann::json warnings = SunBelowLutWarnings(o, preset, elevation);

  render::VulkanOptions vk;
  vk.validation = o.vulkan_validation;
  const auto t_init = Clock::now();
  auto renderer = render::CreateRenderer(o.backend, vk);
  if (o.verbose) Say(o, "backend: " + renderer->Describe());
  std::unique_ptr<clouds::CloudRenderer> cloud_renderer;
  if (cloud_inputs) cloud_renderer = CreateCloudRenderer(o);
  render::RenderRequest request;
  request.sun_dir = g.sun_dir;
  request.width = o.width;
  request.height = o.height;
  request.sun_disc = o.sun_disc;
  request.ground = o.ground;
  const auto t_render = Clock::now();
  g.radiance = renderer->Render(preset, request);
  const auto t_sky = Clock::now();
  nlohmann::json clouds_summary = nullptr;
  if (cloud_inputs) clouds_summary = RenderCloudsOver(o, preset, *cloud_inputs, *cloud_renderer, &g);
  const auto t_done = Clock::now();
  ApplyExposure(o.exposure, &g.radiance);
  nlohmann::json warnings_out = warnings;
  const nlohmann::json gpu = GpuTimes(o, *renderer, cloud_renderer.get(), &warnings_out);
  g.summary = {{"backend", render::ToString(o.backend)},
               {"device", renderer->Describe()},
               {"preset", g.preset_path},
               {"model", render::ToString(preset.variant)},
               {"sun_direction", g.sun_dir},
               {"sun_elevation_deg", elevation},
               {"sun_azimuth_deg", azimuth},
               {"size", {o.width, o.height}},
               {"clouds", clouds_summary},
               {"time_ms",
                {{"init", Ms(t_init, t_render)},
                 {"render", Ms(t_render, t_done)},
                 {"sky", Ms(t_render, t_sky)},
                 {"clouds", Ms(t_sky, t_done)},
                 {"gpu", gpu}}},
               {"warnings", warnings_out}};
  if (o.exposure != 1.0) g.summary["exposure"] = o.exposure;
  return g;
}

namespace {

// Outputs never over inputs, the PNG never over the EXR, and both writable before any render.
void CheckOutputs(const GameRenderFileOptions& f, const std::string& preset_path) {
  std::vector<NamedPath> outputs{{"GameRenderFileOptions::out_exr", f.out_exr}};
  if (!f.out_png.empty()) outputs.push_back({"GameRenderFileOptions::out_png", f.out_png});
  std::vector<NamedPath> inputs = PresetFileInputs("GameRenderOptions::preset_path", preset_path);
  for (const NamedPath& p : CloudInputs(f.render.clouds)) inputs.push_back(p);
  RefuseOutputsOverInputs(outputs, inputs);
  if (!f.out_png.empty()) RefuseOutputsOverInputs({outputs.back()}, {outputs.front()});
  // Fail on unwritable outputs before spending time rendering.
  { AtomicOutput probe(f.out_exr); }
  if (!f.out_png.empty()) { AtomicOutput probe(f.out_png); }
}

// No non-finite value is written (set to 0 and counted); with half output, finite values
// beyond FP16's largest (65504, e.g. the sun's disc) are counted: the EXR writer clamps them.
void MaskForWrite(const GameRenderFileOptions& f, ImageRGB* image) {
  const auto [non_finite, half_clamped] = MaskNonFinite(image, f.half);
  if (non_finite > 0)
    Say(f.render, f.out_exr + ": " + std::to_string(non_finite) +
                      " non-finite values (NaN or inf: invalid input pixels) masked, written as 0");
  if (half_clamped > 0)
    Say(f.render, f.out_exr + ": GameRenderFileOptions::half: " + std::to_string(half_clamped) +
                      " values above 65504 (the half-float maximum, e.g. at the sun) clamped to 65504; "
                      "write float (without GameRenderFileOptions::half) or lower the exposure to keep them");
}

capture::LatLongFrame FrameOf(const GameRenderFileOptions& f, GameImage* g) {
  capture::LatLongFrame frame;
  frame.radiance = std::move(g->radiance);
  if (g->clouds_drawn) {
    frame.planes.push_back({kCloudTransmittancePlane, std::move(g->cloud_transmittance)});
    frame.extra.strings["skycalClouds"] = g->clouds_origin;
    frame.extra.strings["skycalWeatherMap"] = g->weather_map_origin;
    frame.extra.floats["skycalCloudTimeS"] = static_cast<float>(f.render.clouds.time_s);
  }
  frame.sun_direction = g->sun_dir;
  frame.extra.strings["skycalPreset"] = g->preset_path;
  if (f.time_of_day_h) frame.extra.floats["skycalTimeOfDay"] = static_cast<float>(*f.time_of_day_h);
  frame.extra.strings["skycalModel"] = g->summary.at("model").get<std::string>();
  frame.extra.strings["skycalBackend"] = render::ToString(f.render.backend);
  frame.extra.strings["skycalUnits"] = "cd/m^2 per channel, scene-linear Rec.709";
  if (f.render.exposure != 1.0) frame.extra.floats["skycalExposure"] = static_cast<float>(f.render.exposure);
  return frame;
}

// The EXR and the optional PNG preview, committed together (AtomicOutputGroup): a failed
// preview (OCIO, encoding) leaves every file that existed before the run as it was, and
// writes neither. Returns the summary's `png` object.
nlohmann::json WriteOutputs(const GameRenderFileOptions& f, capture::LatLongFrame* frame) {
  MaskForWrite(f, &frame->radiance);
  if (f.out_png.empty()) {
    capture::WriteLatLongFrame(f.out_exr, *frame, f.half);
    return nullptr;
  }
  RefuseReplacingAPresetLut(f.out_exr);
  AtomicOutputGroup group;
  try {
    const std::string exr = group.Add(f.out_exr), png = group.Add(f.out_png);
    capture::WriteLatLongFrame(exr, *frame, f.half);
    color::PreviewOptions po;
    po.exposure_ev = f.png_exposure_ev;
    const color::PreviewReport report = color::WritePreviewPng(frame->radiance, png, po);
    group.Commit();
    return {{"path", f.out_png}, {"exposure_ev", report.exposure_ev}, {"view", report.view},
            {"ocio_config", report.config_path}};
  } catch (const Error& e) {
    throw Error(group.Unstaged(e.what()));
  }
}

nlohmann::json RadianceStats(const ImageRGB& radiance) {
  double max_v = 0.0, sum = 0.0;
  long long n = 0;
  for (float v : radiance.pixels) {
    max_v = std::max(max_v, static_cast<double>(v));
    sum += v;
    ++n;
  }
  return {{"max", max_v}, {"mean", n ? sum / n : 0.0}};
}

}  // namespace

nlohmann::json WriteGameRender(const GameRenderFileOptions& f) {
  const auto t0 = Clock::now();
  std::string why;
  if (!f.IsValid(&why)) throw Error(why);
  CheckOutputs(f, f.render.preset_path.empty() ? DefaultPresetPath() : f.render.preset_path);
  GameImage g = RenderGameImage(f.render);
  capture::LatLongFrame frame = FrameOf(f, &g);
  const nlohmann::json preview = WriteOutputs(f, &frame);
  nlohmann::json summary = std::move(g.summary);
  if (f.render.verbose)
    Say(f.render, "wrote " + f.out_exr + " (" + std::to_string(f.render.width) + "x" + std::to_string(f.render.height) +
                      ", render " + std::to_string(summary["time_ms"]["render"].get<double>()) + " ms)");
  summary["out"] = f.out_exr;
  summary["png"] = preview;
  summary["radiance_cd_m2"] = RadianceStats(frame.radiance);
  summary["time_ms"]["total"] = Ms(t0, Clock::now());
  return summary;
}

}  // namespace skycal::controllers
