#include "probe_predict_verb.h"

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

#include "command_line.h"
#include "option_values.h"
#include "sun_choice.h"
#include "render_verb.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/render/irradiance.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

nlohmann::json Rgb(const render::Rgb& v) { return {v[0], v[1], v[2]}; }

}  // namespace

bool ProbePredictOptions::IsValid(std::string* why) const {
  if (!ValidSunChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir, why)) return false;
  if (!(albedo >= 0.0 && albedo <= 1.0)) {
    *why = "--albedo " + FormatNumber(albedo) + ": expected a value in [0, 1]";
    return false;
  }
  if (normals < 0 || normals > 100000) {
    *why = "--normals " + std::to_string(normals) + ": expected a count in [0, 100000]";
    return false;
  }
  if (width < 4 || width % 2 != 0 || width > 16384) {
    *why = "--sky-width " + std::to_string(width) + ": expected an even pixel count in [4, 16384]";
    return false;
  }
  return true;
}

std::array<double, 3> ProbePredictOptions::SunDirection() const {
  return SunDirectionFromChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir);
}

nlohmann::json RunProbePredictImpl(const ProbePredictOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const std::string preset_path = o.preset_path.empty() ? DefaultPresetPath() : o.preset_path;
  const render::Preset preset = render::LoadPreset(preset_path);
  const auto sun = o.SunDirection();

  std::vector<render::Dir3> normals = {{0.0, 1.0, 0.0}};
  if (o.normals > 0) {
    for (const auto& n : render::FibonacciSphere(o.normals)) normals.push_back(n);
  }
  render::VulkanOptions vk;
  vk.validation = o.vulkan_validation;
  auto renderer = render::CreateRenderer(o.backend, vk);
  Log("probe-predict", "backend: " + renderer->Describe());
  const auto t_predict = Clock::now();
  const render::ProbePrediction p = render::PredictProbe(preset, sun, normals, o.albedo, *renderer, o.width, o.ground);
  const auto t_done = Clock::now();

  nlohmann::json per_normal = nlohmann::json::array();
  for (size_t i = 0; i < normals.size(); ++i) {
    per_normal.push_back({{"normal", p.normals[i]},
                          {"irradiance_lux", Rgb(p.irradiance[i])},
                          {"sky_irradiance_lux", Rgb(p.sky_quadrature[i])},
                          {"sky_irradiance_sh9_lux", Rgb(p.sky_sh[i])},
                          {"ball_radiance_cd_m2", Rgb(p.ball_radiance[i])}});
  }
  nlohmann::json sh = nlohmann::json::array();
  for (const auto& c : p.sh) sh.push_back(Rgb(c));
  std::ostringstream log;
  log << "up normal: E = " << p.irradiance[0][0] << ", " << p.irradiance[0][1] << ", " << p.irradiance[0][2]
      << " lux (sky " << p.sky_quadrature[0][1] << "), ball radiance " << p.ball_radiance[0][1]
      << " cd/m^2 (G); SH-9 sky error max " << p.sh_max_rel_error << " rms " << p.sh_rms_rel_error;
  Log("probe-predict", log.str());
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  return {{"backend", render::ToString(o.backend)},
          {"device", renderer->Describe()},
          {"preset", preset_path},
          {"sun_direction", sun},
          {"sun_elevation_deg", latlong::ElevationDeg(sun)},
          {"sun_azimuth_deg", latlong::AzimuthDeg(sun)},
          {"sun_visible", p.sun_visible},
          {"sun_illuminance_lux", Rgb(p.sun_illuminance)},
          {"albedo", o.albedo},
          {"ground", o.ground == render::GroundMode::kLit ? "lit" : "zero"},
          {"sky_size", {p.width, p.height}},
          {"up", per_normal[0]},
          {"normals", per_normal},
          {"sh9_radiance", sh},
          {"sh9_vs_quadrature",
           {{"sky_max_rel", p.sh_max_rel_error},
            {"sky_rms_rel", p.sh_rms_rel_error},
            {"total_max_rel", p.sh_total_max_rel_error},
            {"total_rms_rel", p.sh_total_rms_rel_error}}},
          {"units", "irradiance lux, radiance cd/m^2, per channel, scene-linear Rec.709"},
          {"time_ms", {{"predict", ms(t_predict, t_done)}, {"total", ms(t0, Clock::now())}}}};
}

ProbePredictOptions ParseProbePredictArgs(int argc, char** argv) {
  VerbCommandLine cl("probe-predict",
                     "skycal probe-predict: predict the gray diffuse probe (irradiance on a ball) from a preset",
                     "  skycal probe-predict [--preset P.json] (--sun-elevation DEG --sun-azimuth DEG | --sun-dir X,Y,Z)\n"
                     "                       [--albedo A] [--normals N] [--backend vulkan|cpu] [--json]",
                     "The sky is rendered without the sun disc (a sub-pixel disc would alias) and the sun adds\n"
                     "E_sun max(0, n.s) analytically. Irradiance in lux per channel, ball radiance albedo/pi * E\n"
                     "in cd/m^2, SH-9 radiance coefficients (Ramamoorthi & Hanrahan 2001), scene-linear Rec.709.");
  ProbePredictOptions o;
  std::optional<std::string> sun_dir, backend, ground;
  bool json = false;
  cl.Text("--preset", &o.preset_path, "P.json", "sky preset (default: the bundled datasets/presets/default_clear.json)");
  cl.Number("--sun-elevation", &o.sun_elevation_deg, "DEG", "sun elevation above the horizon, degrees in [-90, 90]");
  cl.Number("--sun-azimuth", &o.sun_azimuth_deg, "DEG", "sun azimuth = lat-long longitude, degrees (0 -> +Z, 90 -> +X)");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z", "alternative: vector toward the sun (+Y up), normalised");
  cl.Number("--albedo", &o.albedo, "A", "the ball's Lambertian albedo in [0, 1] (default 0.18, a gray card)");
  // Integers here; IsValid holds the ranges ([0, 100000] normals, even width >= 4).
  cl.Integer("--normals", &o.normals, -1e9, 1e9, "expected an integer", "N",
             "Fibonacci-sphere normals besides the up normal (default 64)");
  cl.Integer("--sky-width", &o.width, -1e9, 1e9, "expected an integer", "W",
             "width of the sky render, even, >= 4 (default 512; height W/2)");
  cl.Text("--backend", &backend, "NAME", "vulkan (default; the game's compute shaders) or cpu (double reference)");
  cl.Text("--ground", &ground, "lit|zero", "below the horizon: albedo-lit constant ground (default) or black");
  cl.Flag("--vulkan-validation", &o.vulkan_validation, "enable VK_LAYER_KHRONOS_validation");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (sun_dir) o.sun_dir = ParseVec3(*sun_dir, "--sun-dir");
  if (backend) o.backend = render::ParseBackend(*backend, "--backend");
  if (ground) o.ground = ParseGroundMode(*ground, "--ground");
  return o;
}

int RunProbePredict(int argc, char** argv) {
  return RunVerb("probe-predict", WantsJson(argc, argv),
                 [&]() { return RunProbePredictImpl(ParseProbePredictArgs(argc, argv)); });
}

}  // namespace skycal::cli
