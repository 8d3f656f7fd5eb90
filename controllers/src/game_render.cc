#include "render_verb.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "skycal/core/atomic_file.h"
#include "skycal/core/data_dir.h"

#include "command_line.h"
#include "finite_output.h"
#include "option_values.h"
#include "sun_choice.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"
#include "skycal/core/atomic_output_group.h"
#include "skycal/core/output_kind.h"
#include "skycal/core/latlong.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/composite.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string DefaultPresetPath() { return DataPath("datasets/presets/default_clear.json"); }

bool RenderOptions::IsValid(std::string* why) const {
  if (!ValidSunChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir, why)) return false;
  render::RenderRequest r;
  r.width = width;
  r.height = height;
  if (!r.IsValid(why)) {
    *why = "--size: " + *why;
    return false;
  }
  if (width != 2 * height) {  // the project's lat-long convention; fit and import read 2:1 only
    *why = "--size " + std::to_string(width) + "x" + std::to_string(height) +
           ": expected a 2:1 lat-long (width = 2 x height), as fit and import read";
    return false;
  }
  if (time_of_day_h && !(*time_of_day_h >= 0.0 && *time_of_day_h < 24.0)) {
    *why = "--time-of-day: expected hours in [0, 24)";
    return false;
  }
  if (out_exr.empty() || !EndsWith(out_exr, ".exr")) {
    *why = "--out: expected an output path ending in .exr";
    return false;
  }
  if (!out_png.empty() && !EndsWith(out_png, ".png")) {
    *why = "--png: expected a path ending in .png";
    return false;
  }
  if (!clouds.enabled && (!clouds.weather_map.empty() || clouds.steps || clouds.light_samples || clouds.naive ||
                          clouds.cheap_light_opacity ||
                          clouds.time_s != 0.0)) {
    *why = "--weather-map, --cloud-time, --cloud-steps, --cloud-light-samples, --cloud-cheap-light-opacity and --cloud-naive "
           "need --clouds";
    return false;
  }
  if (!(std::abs(clouds.time_s) <= 1.0e7)) {
    *why = "--cloud-time: expected seconds within [-1e7, 1e7]";
    return false;
  }
  if (!std::isnan(png_exposure_ev) && std::abs(png_exposure_ev) > 64) {
    *why = "--exposure: expected stops in [-64, 64]";
    return false;
  }
  return true;
}

std::array<double, 3> RenderOptions::SunDirection() const {
  return SunDirectionFromChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir);
}

namespace {
// Outputs never over inputs, --png never over --out, and both writable before any render.
void CheckRenderOutputs(const RenderOptions& o, const std::string& preset_path) {
  std::vector<NamedPath> outputs{{"--out", o.out_exr}};
  if (!o.out_png.empty()) outputs.push_back({"--png", o.out_png});
  std::vector<NamedPath> inputs = PresetInputs("--preset", preset_path);
  for (const NamedPath& p : CloudInputs(o.clouds, preset_path)) inputs.push_back(p);
  RefuseOutputsOverInputs(outputs, inputs);
  if (!o.out_png.empty()) RefuseOutputsOverInputs({outputs.back()}, {outputs.front()});  // --png vs --out
  // Fail on unwritable outputs before spending time rendering.
  { AtomicOutput probe(o.out_exr); }
  if (!o.out_png.empty()) { AtomicOutput probe(o.out_png); }
}

// The clouds over the sky in `frame` (disc included: the clouds' transmittance hides it);
// returns render --json's `clouds` object.
nlohmann::json RenderCloudsOver(const RenderOptions& o, const render::Preset& preset, const CloudInputsLoaded& in,
                                const clouds::MarchOptions& march, const latlong::Vec3d& sun,
                                clouds::CloudRenderer& cloud_renderer, capture::LatLongFrame* frame) {
  clouds::CloudRenderRequest cr;
  cr.sun_dir = sun;
  cr.width = o.width;
  cr.height = o.height;
  cr.time_s = o.clouds.time_s;
  cr.march = march;
  const clouds::CloudScene scene{&preset, &in.params, &in.noise, &in.weather};
  const clouds::CloudImage cloud = cloud_renderer.Render(scene, cr);
  frame->radiance = clouds::CompositeClouds(frame->radiance, cloud);
  frame->planes.push_back({"cloudTransmittance", cloud.transmittance});
  frame->extra.strings["skycalClouds"] = in.params_origin;
  frame->extra.strings["skycalWeatherMap"] = in.weather_origin;
  frame->extra.floats["skycalCloudTimeS"] = static_cast<float>(o.clouds.time_s);
  double t_mean = 0.0;
  for (float t : cloud.transmittance) t_mean += t / cloud.transmittance.size();
  return {{"device", cloud_renderer.Describe()},
          {"parameters", in.params_origin},
          {"weather_map", in.weather_origin},
          {"time_s", o.clouds.time_s},
          {"transmittance_mean", t_mean},
          {"steps", {march.steps_zenith, march.steps_horizon}},
          {"light_samples", march.light_samples}};
}

// The EXR and the optional PNG preview, committed together (AtomicOutputGroup): a failed
// preview (OCIO, encoding) leaves every file that existed before the run as it was, and
// writes neither. Returns render --json's `png` object.
nlohmann::json WriteRenderOutputs(const RenderOptions& o, capture::LatLongFrame* frame) {
  PrepareImageForWrite("render", o.out_exr, &frame->radiance, o.half);
  if (o.out_png.empty()) {
    capture::WriteLatLongFrame(o.out_exr, *frame, o.half);
    return nullptr;
  }
  RefuseReplacingAPresetLut(o.out_exr);
  AtomicOutputGroup group;
  try {
    const std::string exr = group.Add(o.out_exr), png = group.Add(o.out_png);
    capture::WriteLatLongFrame(exr, *frame, o.half);
    color::PreviewOptions po;
    po.exposure_ev = o.png_exposure_ev;
    const color::PreviewReport report = color::WritePreviewPng(frame->radiance, png, po);
    group.Commit();
    return {{"path", o.out_png}, {"exposure_ev", report.exposure_ev}, {"view", report.view},
            {"ocio_config", report.config_path}};
  } catch (const Error& e) {
    throw Error(group.Unstaged(e.what()));
  }
}

nlohmann::json SunBelowLutWarnings(const render::Preset& preset, double elevation) {
  nlohmann::json warnings = nlohmann::json::array();
  const double lut_min_elevation = 90.0 - preset.luts.grid.theta_max_deg;
  if (elevation < lut_min_elevation) {
    warnings.push_back("sun elevation " + std::to_string(elevation) + " deg is below the LUT's range (" +
                       std::to_string(lut_min_elevation) + " deg): the last twilight row is used");
  }
  for (const auto& w : warnings) Log("render", "warning: " + w.get<std::string>());
  return warnings;
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

nlohmann::json RunRenderImpl(const RenderOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const std::string preset_path = o.preset_path.empty() ? DefaultPresetPath() : o.preset_path;
  const clouds::MarchOptions march = CloudMarchOptions(o.clouds);
  CheckRenderOutputs(o, preset_path);
  const render::Preset preset = render::LoadPreset(preset_path);
  std::optional<CloudInputsLoaded> cloud_inputs;
  if (o.clouds.enabled) cloud_inputs = LoadCloudInputs(o.clouds, preset, preset_path);  // before any time is spent
  const auto sun = o.SunDirection();
  const double elevation = latlong::ElevationDeg(sun), azimuth = latlong::AzimuthDeg(sun);
  const nlohmann::json warnings = SunBelowLutWarnings(preset, elevation);

  render::VulkanOptions vk;
  vk.validation = o.vulkan_validation;
  const auto t_init = Clock::now();
  auto renderer = render::CreateRenderer(o.backend, vk);
  if (o.verbose) Log("render", "backend: " + renderer->Describe());
  // The cloud pipeline is created (lavapipe compiles the shader) before the render clock starts.
  std::unique_ptr<clouds::CloudRenderer> cloud_renderer;
  if (cloud_inputs) {
    cloud_renderer = o.backend == render::Backend::kVulkan ? clouds::CreateVulkanCloudRenderer(o.vulkan_validation)
                                                           : clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
  }
  render::RenderRequest request;
  request.sun_dir = sun;
  request.width = o.width;
  request.height = o.height;
  request.sun_disc = o.sun_disc;
  request.ground = o.ground;
  const auto t_render = Clock::now();
  capture::LatLongFrame frame;
  frame.radiance = renderer->Render(preset, request);
  const auto t_sky = Clock::now();
  nlohmann::json clouds_summary = nullptr;
  if (cloud_inputs) clouds_summary = RenderCloudsOver(o, preset, *cloud_inputs, march, sun, *cloud_renderer, &frame);
  const auto t_done = Clock::now();
  frame.sun_direction = sun;
  frame.extra.strings["skycalPreset"] = preset_path;
  if (o.time_of_day_h) frame.extra.floats["skycalTimeOfDay"] = static_cast<float>(*o.time_of_day_h);
  frame.extra.strings["skycalModel"] = render::ToString(preset.variant);
  frame.extra.strings["skycalBackend"] = render::ToString(o.backend);
  frame.extra.strings["skycalUnits"] = "cd/m^2 per channel, scene-linear Rec.709";
  const nlohmann::json preview = WriteRenderOutputs(o, &frame);

  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  if (o.verbose)
    Log("render", "wrote " + o.out_exr + " (" + std::to_string(o.width) + "x" + std::to_string(o.height) + ", render " +
                    std::to_string(ms(t_render, t_done)) + " ms)");
  return {{"backend", render::ToString(o.backend)},
          {"device", renderer->Describe()},
          {"preset", preset_path},
          {"model", render::ToString(preset.variant)},
          {"sun_direction", sun},
          {"sun_elevation_deg", elevation},
          {"sun_azimuth_deg", azimuth},
          {"size", {o.width, o.height}},
          {"out", o.out_exr},
          {"png", preview},
          {"radiance_cd_m2", RadianceStats(frame.radiance)},
          {"clouds", clouds_summary},
          {"time_ms",
           {{"init", ms(t_init, t_render)},
            {"render", ms(t_render, t_done)},
            {"sky", ms(t_render, t_sky)},
            {"clouds", ms(t_sky, t_done)},
            {"total", ms(t0, Clock::now())}}},
          {"warnings", warnings}};
}

render::GroundMode ParseGroundMode(const std::string& text, const std::string& option) {
  if (text == "lit") return render::GroundMode::kLit;
  if (text == "zero") return render::GroundMode::kZero;
  throw Error(option + ": unknown mode '" + text + "' (expected lit or zero)");
}

RenderOptions ParseRenderArgs(int argc, char** argv) {
  VerbCommandLine cl("render", "skycal render: render a sky preset to a lat-long EXR",
                     "  skycal render [--preset P.json] (--sun-elevation DEG --sun-azimuth DEG | --sun-dir X,Y,Z)\n"
                     "                [--size WxH] [--backend vulkan|cpu] --out OUT.exr [--png OUT.png] [--json]\n"
                     "                [--clouds [--weather-map W.exr] [--cloud-time S] [--cloud-steps Z,H] [--cloud-cheap-light-opacity O] [--cloud-naive]]",
                     "Output units: cd/m^2 per channel, scene-linear Rec.709.");
  RenderOptions o;
  std::optional<std::string> sun_dir, size, backend, ground;
  bool no_sun_disc = false, json = false;
  cl.Text("--preset", &o.preset_path, "P.json", "sky preset (default: the bundled datasets/presets/default_clear.json)");
  cl.Number("--sun-elevation", &o.sun_elevation_deg, "DEG", "sun elevation above the horizon, degrees in [-90, 90]");
  cl.Number("--sun-azimuth", &o.sun_azimuth_deg, "DEG", "sun azimuth = lat-long longitude, degrees (0 -> +Z, 90 -> +X)");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z", "alternative: vector toward the sun (+Y up), normalised");
  cl.Number("--time-of-day", &o.time_of_day_h, "HOURS",
            "local time of the frame, hours in [0, 24): written as the skycalTimeOfDay\n"
            "attribute (fit records it; batch orders a day's frames by it)");
  cl.Text("--size", &size, "WxH", "image size in pixels, a 2:1 lat-long (W = 2H), at most 32768x16384 (default 1024x512)");
  cl.Text("--backend", &backend, "NAME", "vulkan (default; the game's compute shaders) or cpu (double reference)");
  cl.Text("--ground", &ground, "lit|zero", "below the horizon: albedo-lit constant ground (default) or black");
  cl.Flag("--no-sun-disc", &no_sun_disc, "leave the sun disc out");
  cl.Flag("--half", &o.half, "write half floats (default float)");
  cl.Text("--out", &o.out_exr, "OUT.exr", "output lat-long EXR (envmap=latlong, sunDirection attributes; required)");
  cl.Text("--png", &o.out_png, "OUT.png", "preview PNG through the OCIO view transform ($OCIO or config/skycal.ocio)");
  cl.Number("--exposure", &o.png_exposure_ev, "EV", "preview exposure in stops (default: automatic, log-average -> 0.18)");
  cl.Flag("--vulkan-validation", &o.vulkan_validation, "enable VK_LAYER_KHRONOS_validation");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Flag("--clouds", &o.clouds.enabled,
          "composite HZD volumetric clouds over the sky: the preset's `clouds` section, or the bundled "
          "datasets/presets/default_cloudy.json's when it has none; the EXR gains a cloudTransmittance channel");
  cl.Text("--weather-map", &o.clouds.weather_map, "W.exr",
          "with --clouds: weather map (RGB EXR: coverage, precipitation, type; square, power of two) instead of the section's");
  cl.Number("--cloud-time", &o.clouds.time_s, "S", "with --clouds: time in seconds; the wind moves the clouds by speed x time (default 0)");
  cl.Text("--cloud-steps", &o.clouds.steps, "Z,H",
          "with --clouds: primary samples looking up and at the horizon, each 1..4096 (default 64,128, HZD's)");
  cl.Text("--cloud-light-samples", &o.clouds.light_samples, "N", "with --clouds: samples toward the sun, 0..64 (default 6)");
  cl.Text("--cloud-cheap-light-opacity", &o.clouds.cheap_light_opacity, "O",
          "with --clouds: opacity 0..1 past which light samples read the base shape only (default 0.3, HZD's; 0.6: "
          "about a quarter of the added error at the same lavapipe time, docs/cloud-model.md)");
  cl.Flag("--cloud-naive", &o.clouds.naive, "with --clouds: every HZD march optimisation off (for measurement)");
  cl.Parse(argc, argv);
  if (sun_dir) o.sun_dir = ParseVec3(*sun_dir, "--sun-dir");
  if (size) {
    const auto wh = ParseSize(*size, "--size");
    o.width = wh[0];
    o.height = wh[1];
  }
  if (backend) o.backend = render::ParseBackend(*backend, "--backend");
  if (ground) o.ground = ParseGroundMode(*ground, "--ground");
  o.sun_disc = !no_sun_disc;
  return o;
}

int RunRender(int argc, char** argv) {
  return RunVerb("render", WantsJson(argc, argv), [&]() { return RunRenderImpl(ParseRenderArgs(argc, argv)); });
}

}  // namespace skycal::cli
