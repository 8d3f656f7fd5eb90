#include "fit_verb.h"

#include <optional>

#include "command_line.h"
#include "fit_option_args.h"
#include "option_values.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "verb_common.h"

namespace skycal::cli {

std::string WithFitControllerFlags(const std::string& message) {
  // Whole messages first (the checks the verb once wrote itself), then each field.
  static const FieldFlag kFlags[] = {
      {"FitControllerOptions::references is empty (expected at least one lat-long EXR)",
       "at least one --reference is required"},
      {"FitControllerOptions::out_dir is empty (expected a directory)", "--out DIR is required"},
      {"FitCloudStatsOptions::enabled = true", "--clouds stats"},
      {"FitControllerOptions::cloud_mask = true", "--cloud-mask"},
      {"FitControllerOptions::report = false", "--no-report"},
      {"FitControllerOptions::references", "--reference"},
      {"FitControllerOptions::out_dir", "--out"},
      {"FitControllerOptions::init_preset", "--init"},
      {"FitControllerOptions::probes", "--probe"},
      {"FitControllerOptions::require_probe", "--require-probe"},
      {"FitOptions::mask_path", "--mask"},
      {"FitCloudOptions::mode", "--clouds"},
      {"FitCloudOptions::preset", "--cloud-preset"},
      {"FitCloudOptions::time_s", "--cloud-time"},
      {"CloudLightingOptions::samples", "--cloud-samples"},
      {"CloudLightingOptions::day_smoothness", "--cloud-day-smoothness"},
      {"CloudLightingOptions::hold", "--cloud-hold"},
      {"CloudMode on", "--clouds on"},
      {"CloudMode off", "--clouds off"},
      {"CloudMode auto", "--clouds auto"},
      {"KnownCloudShapes", "--cloud-preset"}};
  return WithCloudStatsFlags(FieldsAsFlags(message, kFlags));
}

std::string WithCloudStatsFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"FitPhotoCloudStats:", "--clouds stats:"},
                                     {"PhotoCloudStatsOptions::width", "--cloud-stats-width"},
                                     {"PhotoCloudStatsOptions::maps", "--cloud-stats-maps"},
                                     {"PhotoCloudStatsOptions::renders", "cloud stats renders per evaluation"},
                                     {"PhotoCloudStatsOptions::max_iterations", "--cloud-stats-iterations"},
                                     {"PhotoCloudStatsOptions::sun", "--cloud-stats-sun"},
                                     {"PhotoCloudStatsOptions::probability", "--cloud-stats-probability"},
                                     {"PhotoCloudStatsOptions::sun_scale", "--cloud-stats-sun-scale"}};
  return FieldsAsFlags(message, kFlags);
}

bool FitCloudStatsOptions::IsValid(std::string* why) const {
  if (controllers::FitCloudStatsOptions::IsValid(why)) return true;
  *why = WithCloudStatsFlags(*why);
  return false;
}

nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<cloudfit::CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const std::filesystem::path& fit_dir,
                                     cloudfit::CloudStatsPresetUpdate* update) {
  try {
    return controllers::RunCloudStatsOnPhotos(o, photos, sky, fit_dir, update);
  } catch (const Error& e) {
    throw Error(WithCloudStatsFlags(e.what()));
  }
}

namespace {

controllers::FitControllerOptions ControllerOptions(const FitVerbOptions& o) {
  controllers::FitControllerOptions c;
  c.references = o.references;
  c.init_preset = o.init_preset;
  c.out_dir = o.out_dir;
  c.fit = o.fit;
  c.cloud_mask = o.cloud_mask;
  c.report = o.report;
  return c;
}

// The controller's check with fields written as flags (FitOptions' too).
bool ValidWithFlags(const controllers::FitControllerOptions& o, std::string* why) {
  if (o.IsValid(why)) return true;
  *why = WithFitFlags(WithFitControllerFlags(*why));
  return false;
}

}  // namespace

bool FitVerbOptions::IsValid(std::string* why) const { return ValidWithFlags(ControllerOptions(*this), why); }

controllers::FitControllerOptions FitCommandLine::Controller() const {
  controllers::FitControllerOptions c = ControllerOptions(options);
  c.probes = probes.probes;
  c.require_probe = probes.require_probe;
  c.clouds = clouds;
  c.cloud_stats = cloud_stats;
  return c;
}

nlohmann::json RunFitImpl(const FitCommandLine& c) {
  const controllers::FitControllerOptions o = c.Controller();
  std::string why;
  if (!ValidWithFlags(o, &why)) throw Error(why);
  try {
    return controllers::RunFitController(o);
  } catch (const Error& e) {
    throw Error(WithFitControllerFlags(e.what()));
  }
}

nlohmann::json RunFitImpl(const FitVerbOptions& o) {
  FitCommandLine c;
  c.options = o;
  return RunFitImpl(c);
}

namespace {

// The --clouds family of fit's options (docs/cloud-fitting.md).
void RegisterFitCloudArgs(VerbCommandLine& cl, FitCommandLine* c) {
  cl.Text("--clouds", &c->clouds.mode, "MODE",
          "auto (default), on, off or stats: fit the cloud lighting too (on: per reference; a day\n"
          "of references adds a smoothness prior over time of day, --cloud-day-smoothness).\n"
          "auto: on when the reference's cloud mask finds >= 1% cloud pixels and\n"
          "--cloud-preset gives the shapes; a clear reference never marches clouds.\n"
          "stats: unknown shapes (a photograph): implies --cloud-mask; the atmosphere\n"
          "fits the clear pixels, then the cloud lighting fits statistics of the cloud\n"
          "pixels (fit.json's cloud_stats, fit/<ref>.clouds.*.png)");
  cl.Text("--cloud-preset", &c->clouds.preset, "PRESET.json",
          "the known cloud shapes: a preset whose clouds section (shape fields, start\n"
          "lighting) and weather map rendered the reference (e.g. default_cloudy.json)");
  cl.Number("--cloud-time", &c->clouds.time_s, "S",
            "wind time of the references' clouds, seconds (default: each reference's\n"
            "skycalCloudTimeS attribute, written by render --clouds, else 0)");
  cl.Number("--cloud-day-smoothness", &c->clouds.day_smoothness, "L",
            "a day of >= 3 references: weight of the second-difference prior on each cloud\n"
            "lighting parameter over time of day (relative change per h^2; default 0.02, 0: off)");
  cl.Integer("--cloud-samples", &c->clouds.samples, -1e9, 1e9, "expected an integer", "N",
             "cloud pixels in the Jet Jacobian (default 256; all when fewer)");
  cl.Repeatable("--cloud-hold", &c->clouds.hold, "NAME", "hold a cloud lighting parameter at the preset's value (repeatable)");
  cl.Integer("--cloud-stats-width", &c->cloud_stats.width, 16, 1024, "expected pixels in [16, 1024]", "PX",
             "--clouds stats: width of the statistics' lat-long renders (default 128; the\n"
             "frame, at least as wide, is averaged down to it)");
  cl.Integer("--cloud-stats-maps", &c->cloud_stats.maps, 1, 16, "expected an integer in [1, 16]", "N",
             "--clouds stats: weather maps (shape draws) the model pools (default 4; 2 renders each)");
  cl.Integer("--cloud-stats-iterations", &c->cloud_stats.max_iterations, 0, 200, "expected an integer in [0, 200]", "N",
             "--clouds stats: Ceres iterations at most (default 12)");
  cl.Text("--cloud-stats-sun", &c->cloud_stats.sun, "photo|model",
          "--clouds stats: the sun lighting the model's clouds: the photo's disc (lux in model\n"
          "units, fit.json's sun_check; default photo) or the fitted preset's (model)");
  cl.Text("--cloud-stats-probability", &c->cloud_stats.probability, "fitted|initial",
          "--clouds stats: the cloud probability's clear-sky expectation: also the sky fit's own\n"
          "render (cloud where both say so; default fitted) or --cloud-mask's alone (initial)");
  cl.Text("--cloud-stats-sun-scale", &c->cloud_stats.sun_scale, "fit|off",
          "--clouds stats: fit: albedo held at water's physical 0.9999, a scale on the sun (>= 1 where\n"
          "the disc is saturated) fitted with the ambient (default); off: the sun as measured, albedo fitted");
}

// --clouds MODE as the controllers take it: stats means unknown shapes, the statistics stage
// and --cloud-mask, with no known-shapes term.
void ApplyFitCloudMode(FitCommandLine* c) {
  c->cloud_stats.renders = 2 * c->cloud_stats.maps;
  if (c->clouds.mode != "auto" && c->clouds.mode != "on" && c->clouds.mode != "off" && c->clouds.mode != "stats") {
    throw Error("--clouds: unknown mode '" + c->clouds.mode + "' (expected auto, on, off or stats)");
  }
  if (c->clouds.mode == "stats") {
    if (!c->clouds.preset.empty()) throw Error("--clouds stats: the shapes are unknown: --cloud-preset does not apply");
    c->cloud_stats.enabled = true;
    c->clouds.mode = "off";  // no known-shapes term
    c->options.cloud_mask = true;
  }
}

}  // namespace

FitCommandLine ParseFitArgs(int argc, char** argv) {
  VerbCommandLine cl("fit", "skycal fit: fit the sky model to HDR reference skies",
                     "  skycal fit --reference REF.exr [--reference REF2.exr ...] [--model ffxv|ffxv-iso]\n"
                     "             [--backend vulkan|cpu] [--sun-dir X,Y,Z | --sun-elevation DEG --sun-azimuth DEG]\n"
                     "             [--mask MASK.exr] [--init PRESET.json] --out DIR [--json]\n"
                     "             [--clouds auto|on|off|stats] [--cloud-preset P.json] [--cloud-time S]\n"
                     "             [--cloud-stats-width PX] [--cloud-stats-maps N] [--cloud-stats-iterations N]\n"
                     "             [--cloud-stats-sun photo|model] [--cloud-stats-probability fitted|initial]\n"
                     "             [--cloud-stats-sun-scale fit|off]");
  FitCommandLine c;
  FitVerbOptions& o = c.options;
  fit::FitOptions& f = o.fit;
  std::optional<std::string> sun_dir;
  std::optional<double> el, az;
  FitOptionArgs fa;
  bool json = false;
  cl.Repeatable("--reference", &o.references, "F.exr", "lat-long EXR (project convention); repeat for a day of references");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z",
          "sun direction for every reference (else the EXR's sunDirection\n"
          "attribute, else detected in the image, with a warning)");
  cl.Number("--sun-elevation", &el, "DEG", "alternative to --sun-dir, with --sun-azimuth: degrees in [-90, 90]");
  cl.Number("--sun-azimuth", &az, "DEG", "lat-long longitude of the sun, degrees (0 -> +Z, 90 -> +X)");
  cl.Number("--time", &f.time_of_day_h, "HOURS", "time of day of the reference(s), recorded for `skycal export`");
  RegisterFitOptionArgs(cl, &fa, &f, &o.init_preset);
  cl.Repeatable("--probe", &c.probes.probes, "STEM=S.json",
                "probe samples (skycal probe-extract) for the reference named STEM\n"
                "(repeatable; default: <reference without .exr>.probe.json when present):\n"
                "the ball's samples join the fit as residuals; the sun's RGB illuminance\n"
                "(per reference) and the ground albedo become fitted parameters");
  cl.Flag("--require-probe", &c.probes.require_probe, "error unless every reference has probe samples");
  cl.Flag("--cloud-mask", &o.cloud_mask,
          "leave cloudy pixels out (cloud probability >= 0.5: the frame's mask.cloud channel,\n"
          "else estimated from colour against the bundled clear preset at the frame's sun)");
  cl.Text("--out", &o.out_dir, "DIR",
          "output directory (required): preset.json (+ LUT EXRs), fit/<ref>.exr and\n"
          "fit/<ref>.{reference,fit,error}.png, report.png, fit.json, report.html");
  bool no_report = false;
  cl.Flag("--no-report", &no_report, "do not write DIR/report.html (skycal report)");
  RegisterFitCloudArgs(cl, &c);
  cl.Flag("--json", &json, "print fit.json on stdout");
  cl.Parse(argc, argv);
  ApplyFitCloudMode(&c);
  ApplyFitOptionArgs(fa, &f);
  if (sun_dir && (el || az)) throw Error("give either --sun-dir or --sun-elevation/--sun-azimuth, not both");
  if (el.has_value() != az.has_value()) throw Error("--sun-elevation and --sun-azimuth go together");
  if (el && (*el < -90.0 || *el > 90.0)) throw Error("--sun-elevation: expected degrees in [-90, 90]");
  if (el) f.sun_dir = latlong::DirectionFromElevationAzimuthDeg(*el, *az);
  if (sun_dir) f.sun_dir = ParseVec3(*sun_dir, "--sun-dir");
  o.report = !no_report;
  // --cloud-mask takes the cloud pixels out of the fit; --clouds on fits them.
  if (o.cloud_mask && c.clouds.mode == "on")
    throw Error("--cloud-mask leaves the cloud pixels out and --clouds on fits their lighting: give one of them");
  return c;
}

int RunFit(int argc, char** argv) {
  return RunVerb("fit", WantsJson(argc, argv), [&]() { return RunFitImpl(ParseFitArgs(argc, argv)); });
}

}  // namespace skycal::cli
