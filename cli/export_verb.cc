#include "export_verb.h"

#include <optional>
#include <string>

#include "command_line.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {

namespace {

// The export library's messages name ExportOptions' fields; the user set them with these flags.
std::string WithExportFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"ExportOptions::presets", "--preset"},
                                     {"ExportOptions::out_dir", "--out"},
                                     {"ExportOptions::headroom", "--headroom"},
                                     {"ExportOptions::fog_sigma_deg", "--fog-sigma-deg"},
                                     {"ExportOptions::report = false", "--no-report"}};
  return FieldsAsFlags(message, kFlags);
}

}  // namespace

nlohmann::json RunExportImpl(const ExportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(WithExportFlags(why));
  try {
    return exporter::ExportGameTables(o);
  } catch (const Error& e) {
    throw Error(WithExportFlags(e.what()));
  }
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
