#include "render_verb.h"

#include <limits>

#include "command_line.h"
#include "option_values.h"
#include "sun_choice.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

// The library's messages and log lines name GameRenderOptions' fields; the user set them
// with these flags. Its sun is a vector: the sun flags are checked here (sun_choice.h).
std::string WithRenderFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"GameRenderOptions::width x height", "--size"},
                                     {"GameRenderOptions::preset_path", "--preset"},
                                     {"GameCloudOptions::weather_map", "--weather-map"},
                                     {"GameCloudOptions::time_s", "--cloud-time"},
                                     {"GameRenderFileOptions::time_of_day_h", "--time-of-day"},
                                     {"GameRenderFileOptions::out_exr", "--out"},
                                     {"GameRenderFileOptions::out_png", "--png"},
                                     {"GameRenderFileOptions::png_exposure_ev", "--exposure"},
                                     {"GameRenderFileOptions::half", "--half"}};
  return FieldsAsFlags(message, kFlags);
}

controllers::GameRenderFileOptions ToGameRender(const RenderOptions& o, const clouds::MarchOptions& march) {
  controllers::GameRenderFileOptions f;
  controllers::GameRenderOptions& r = f.render;
  r.preset_path = o.preset_path;
  r.sun_dir = o.SunDirection();
  r.width = o.width;
  r.height = o.height;
  r.backend = o.backend;
  r.ground = o.ground;
  r.sun_disc = o.sun_disc;
  r.vulkan_validation = o.vulkan_validation;
  r.clouds = ToGameClouds(o.clouds, march);
  r.verbose = o.verbose;
  r.log = [](const std::string& line) { Log("render", WithRenderFlags(line)); };
  f.out_exr = o.out_exr;
  f.out_png = o.out_png;
  f.half = o.half;
  f.png_exposure_ev = o.png_exposure_ev;
  f.time_of_day_h = o.time_of_day_h;
  return f;
}

}  // namespace

// The sun flags first, then the library's checks in the verb's order, with the one check
// that is the command line's alone (cloud flags without --clouds) where it has always been:
// after --png's, before --exposure's.
bool RenderOptions::IsValid(std::string* why) const {
  if (!ValidSunChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir, why)) return false;
  controllers::GameRenderFileOptions f;
  try {
    f = ToGameRender(*this, clouds::MarchOptions{});
  } catch (const Error& e) {  // a --sun-dir whose length overflows: latlong::Normalized names it
    *why = e.what();
    return false;
  }
  f.png_exposure_ev = std::numeric_limits<double>::quiet_NaN();
  if (!f.IsValid(why)) {
    *why = WithRenderFlags(*why);
    return false;
  }
  if (!clouds.enabled && (!clouds.weather_map.empty() || clouds.steps || clouds.light_samples || clouds.naive ||
                          clouds.cheap_light_opacity || clouds.time_s != 0.0)) {
    *why = "--weather-map, --cloud-time, --cloud-steps, --cloud-light-samples, --cloud-cheap-light-opacity and --cloud-naive "
           "need --clouds";
    return false;
  }
  f.png_exposure_ev = png_exposure_ev;
  if (!f.IsValid(why)) {
    *why = WithRenderFlags(*why);
    return false;
  }
  return true;
}

std::array<double, 3> RenderOptions::SunDirection() const {
  return SunDirectionFromChoice(sun_elevation_deg, sun_azimuth_deg, sun_dir);
}

nlohmann::json RunRenderImpl(const RenderOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const clouds::MarchOptions march = CloudMarchOptions(o.clouds);
  try {
    return controllers::WriteGameRender(ToGameRender(o, march));
  } catch (const Error& e) {
    throw Error(WithRenderFlags(e.what()));
  }
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
