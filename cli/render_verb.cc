#include "render_verb.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "skycal/core/atomic_file.h"

#include "args.h"
#include "sun_choice.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

constexpr const char* kHelp = R"(skycal render: render a sky preset to a lat-long EXR

  skycal render [--preset P.json] (--sun-elevation DEG --sun-azimuth DEG | --sun-dir X,Y,Z)
                [--size WxH] [--backend vulkan|cpu] --out OUT.exr [--png OUT.png] [--json]

  --preset P.json        sky preset (default: the bundled datasets/presets/default_clear.json)
  --sun-elevation DEG    sun elevation above the horizon, degrees in [-90, 90]
  --sun-azimuth DEG      sun azimuth = lat-long longitude, degrees (0 -> +Z, 90 -> +X)
  --sun-dir X,Y,Z        alternative: vector toward the sun (+Y up), normalised
  --size WxH             image size in pixels (default 1024x512; lat-long wants W = 2H)
  --backend NAME         vulkan (default; the game's compute shaders) or cpu (double reference)
  --ground lit|zero      below the horizon: albedo-lit constant ground (default) or black
  --no-sun-disc          leave the sun disc out
  --half                 write half floats (default float)
  --out OUT.exr          output lat-long EXR (envmap=latlong, sunDirection attributes)
  --png OUT.png          preview PNG through the OCIO view transform ($OCIO or config/skycal.ocio)
  --exposure EV          preview exposure in stops (default: automatic, log-average -> 0.18)
  --vulkan-validation    enable VK_LAYER_KHRONOS_validation
  --json                 print a JSON summary on stdout (the log goes to stderr)
Output units: cd/m^2 per channel, scene-linear Rec.709.
)";

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string DefaultPresetPath() { return std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json"; }

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
  if (out_exr.empty() || !EndsWith(out_exr, ".exr")) {
    *why = "--out: expected an output path ending in .exr";
    return false;
  }
  if (!out_png.empty() && !EndsWith(out_png, ".png")) {
    *why = "--png: expected a path ending in .png";
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

nlohmann::json RunRenderImpl(const RenderOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const std::string preset_path = o.preset_path.empty() ? DefaultPresetPath() : o.preset_path;
  std::vector<NamedPath> outputs{{"--out", o.out_exr}};
  if (!o.out_png.empty()) outputs.push_back({"--png", o.out_png});
  RefuseOutputsOverInputs(outputs, PresetInputs("--preset", preset_path));
  RefuseOutputsOverInputs({outputs.back()}, {outputs.front()});
  // Fail on unwritable outputs before spending time rendering.
  { AtomicOutput probe(o.out_exr); }
  if (!o.out_png.empty()) { AtomicOutput probe(o.out_png); }

  const render::Preset preset = render::LoadPreset(preset_path);
  const auto sun = o.SunDirection();
  const double elevation = latlong::ElevationDeg(sun), azimuth = latlong::AzimuthDeg(sun);
  nlohmann::json warnings = nlohmann::json::array();
  const double lut_min_elevation = 90.0 - preset.luts.grid.theta_max_deg;
  if (elevation < lut_min_elevation) {
    warnings.push_back("sun elevation " + std::to_string(elevation) + " deg is below the LUT's range (" +
                       std::to_string(lut_min_elevation) + " deg): the last twilight row is used");
  }
  for (const auto& w : warnings) Log("render", "warning: " + w.get<std::string>());

  render::VulkanOptions vk;
  vk.validation = o.vulkan_validation;
  const auto t_init = Clock::now();
  auto renderer = render::CreateRenderer(o.backend, vk);
  Log("render", "backend: " + renderer->Describe());
  render::RenderRequest request;
  request.sun_dir = sun;
  request.width = o.width;
  request.height = o.height;
  request.sun_disc = o.sun_disc;
  request.ground = o.ground;
  const auto t_render = Clock::now();
  capture::LatLongFrame frame;
  frame.radiance = renderer->Render(preset, request);
  const auto t_done = Clock::now();
  frame.sun_direction = sun;
  frame.extra.strings["skycalPreset"] = preset_path;
  frame.extra.strings["skycalModel"] = render::ToString(preset.variant);
  frame.extra.strings["skycalBackend"] = render::ToString(o.backend);
  frame.extra.strings["skycalUnits"] = "cd/m^2 per channel, scene-linear Rec.709";

  capture::WriteLatLongFrame(o.out_exr, frame, o.half);
  nlohmann::json preview = nullptr;
  if (!o.out_png.empty()) {
    try {
      color::PreviewOptions po;
      po.exposure_ev = o.png_exposure_ev;
      const color::PreviewReport report = color::WritePreviewPng(frame.radiance, o.out_png, po);
      preview = {{"path", o.out_png}, {"exposure_ev", report.exposure_ev}, {"view", report.view},
                 {"ocio_config", report.config_path}};
    } catch (...) {
      std::filesystem::remove(o.out_exr);  // no partial output: both files or none
      throw;
    }
  }

  double max_v = 0.0, sum = 0.0;
  long long n = 0;
  for (float v : frame.radiance.pixels) {
    max_v = std::max(max_v, static_cast<double>(v));
    sum += v;
    ++n;
  }
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
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
          {"radiance_cd_m2", {{"max", max_v}, {"mean", n ? sum / n : 0.0}}},
          {"time_ms", {{"init", ms(t_init, t_render)}, {"render", ms(t_render, t_done)}, {"total", ms(t0, Clock::now())}}},
          {"warnings", warnings}};
}

int RunRender(int argc, char** argv) {
  if (WantsHelp(argc, argv)) {
    std::cout << kHelp;
    return 0;
  }
  const bool json = WantsJson(argc, argv);
  return RunVerb("render", json, [&]() {
    Args a(argc, argv,
           {"preset", "sun-elevation", "sun-azimuth", "sun-dir", "size", "backend", "ground", "out", "png", "exposure"},
           {"no-sun-disc", "half", "vulkan-validation", "json"});
    RenderOptions o;
    o.preset_path = a.Value("preset").value_or("");
    o.sun_elevation_deg = a.Number("sun-elevation");
    o.sun_azimuth_deg = a.Number("sun-azimuth");
    o.sun_dir = a.Vec3("sun-dir");
    if (auto s = a.Size("size")) {
      o.width = (*s)[0];
      o.height = (*s)[1];
    }
    if (auto b = a.Value("backend")) o.backend = render::ParseBackend(*b, "--backend");
    if (auto g = a.Value("ground")) {
      if (*g == "lit") o.ground = render::GroundMode::kLit;
      else if (*g == "zero") o.ground = render::GroundMode::kZero;
      else throw Error("--ground: unknown mode '" + *g + "' (expected lit or zero)");
    }
    o.sun_disc = !a.Has("no-sun-disc");
    o.half = a.Has("half");
    o.out_exr = a.Value("out").value_or("");
    o.out_png = a.Value("png").value_or("");
    if (auto e = a.Number("exposure")) o.png_exposure_ev = *e;
    o.vulkan_validation = a.Has("vulkan-validation");
    return RunRenderImpl(o);
  });
}

}  // namespace skycal::cli
