#include "calibrate_verb.h"

#include "command_line.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

// The controller's fields as the user typed them.
const FieldFlag kFlags[] = {{"CalibrateOptions::photos", "--photo"},
                            {"CalibrateOptions::out_dir", "--out"},
                            {"CalibrateOptions::time_iso8601", "--time"},
                            {"CalibrateOptions::latitude_deg", "--lat"},
                            {"CalibrateOptions::longitude_deg", "--lon"},
                            {"CalibrateOptions::north_longitude_deg", "--north"},
                            {"CalibrateOptions::sun_elevation_deg", "--sun-elevation"},
                            {"CalibrateOptions::sun_azimuth_deg", "--sun-azimuth"},
                            {"CalibrateOptions::invert_weather is off", "--no-weather-inversion was given"},
                            {"CalibrateOptions::weather_map", "--weather-map"},
                            {"time_iso8601", "--time"},
                            {"latitude_deg", "--lat"},
                            {"longitude_deg", "--lon"},
                            {"sun_elevation_deg", "--sun-elevation"},
                            {"sun_azimuth_deg", "--sun-azimuth"}};

nlohmann::json PhotoJson(const controllers::PhotoCalibration& p) {
  nlohmann::json j = {{"photo", p.photo}, {"seconds", p.seconds}};
  if (p.dir.empty()) {
    j["calibrated"] = false;
    j["reason"] = FieldsAsFlags(p.refusal, kFlags);
    return j;
  }
  const fit::FitCalibration& c = *p.calibration;
  j["calibrated"] = true;
  j["dir"] = p.dir;
  j["sky_kind"] = c.sky_kind;
  j["sky_kind_reason"] = c.sky_kind_reason;
  j["sun_source"] = c.sun_source;
  j["sun_uncertainty_deg"] = c.sun_uncertainty_deg ? nlohmann::json(*c.sun_uncertainty_deg) : nlohmann::json();
  j["game_per_pixel_log_rmse"] = c.game_per_pixel_log_rmse;
  j["game_appearance_error"] = c.game_appearance_error;
  if (c.game_cloud_iou) j["game_cloud_iou"] = *c.game_cloud_iou;
  return j;
}

}  // namespace

nlohmann::json RunCalibrateImpl(const controllers::CalibrateOptions& o) {
  controllers::CalibrateResult r;
  try {
    r = controllers::RunCalibrate(o);
  } catch (const Error& e) {
    throw Error(FieldsAsFlags(e.what(), kFlags));
  }
  nlohmann::json photos = nlohmann::json::array();
  for (const controllers::PhotoCalibration& p : r.photos) photos.push_back(PhotoJson(p));
  const int refused = static_cast<int>(r.photos.size()) - r.calibrated();
  Log("calibrate", std::to_string(r.calibrated()) + " of " + std::to_string(r.photos.size()) + " photo(s) calibrated into " +
                       o.out_dir + (r.game_dir.empty() ? "" : "; game tables in " + r.game_dir) +
                       (r.report_path.empty() ? "" : "; open " + r.report_path));
  for (const controllers::PhotoCalibration& p : r.photos)
    if (p.dir.empty()) Log("calibrate", FieldsAsFlags(p.refusal, kFlags));
  return {{"out", o.out_dir},     {"photos", photos},         {"calibrated", r.calibrated()},
          {"refused", refused},    {"game", r.game_dir},       {"report", r.report_path},
          {"warnings", r.warnings}, {"seconds", r.seconds},    {"verb_failed", refused > 0}};
}

controllers::CalibrateOptions ParseCalibrateArgs(int argc, char** argv) {
  VerbCommandLine cl("calibrate",
                     "skycal calibrate: photographs of the sky in, calibrated presets, game tables and a report out",
                     "  skycal calibrate --photo P.exr|P.hdr|FOLDER [--photo ...] --out DIR [--time ISO8601 --lat DEG --lon DEG [--north DEG]]\n"
                     "                   [--sun-elevation DEG --sun-azimuth DEG] [--no-weather-inversion | --weather-map W.exr]\n"
                     "                   [--no-export] [--no-report] [--quiet] [--json]",
                     "Per photo, into DIR/<stem>/: the sky found (mask.exr), the sun placed (disc, time and place, or\n"
                     "the sky's own pattern), the kind of sky decided (clear, partly cloudy, overcast, twilight; night\n"
                     "and not-a-sky are refused), the fit (preset.json, fit.json), the game's image of the calibrated\n"
                     "preset (render.exr) and the photo beside it (compare.png, report.html). Partly cloudy photos\n"
                     "that carry their times: one wind for the day (DIR/day.json, written into their presets). Then\n"
                     "DIR/game (the game tables) and DIR/report.html. Exit 1 when a photo was not calibrated (the\n"
                     "others are written). docs/calibrate.md.");
  controllers::CalibrateOptions o;
  cl.Repeatable("--photo", &o.photos, "P.exr|P.hdr|FOLDER",
                "a lat-long HDR photo (OpenEXR or Radiance .hdr, either convention `import` reads), or a folder: its "
                "pictures in name order; repeatable");
  cl.Text("--out", &o.out_dir, "DIR", "output directory (required)");
  cl.Text("--time", &o.time_iso8601, "ISO8601", "when the photos were taken, with a UTC offset (2026-06-21T06:30+02:00)");
  cl.Number("--lat", &o.latitude_deg, "DEG", "where: latitude, north positive");
  cl.Number("--lon", &o.longitude_deg, "DEG", "where: longitude, east positive");
  cl.Number("--north", &o.north_longitude_deg, "DEG", "lat-long longitude of geographic north (default: the sky gives the azimuth)");
  cl.Number("--sun-elevation", &o.sun_elevation_deg, "DEG", "the sun given outright: elevation");
  cl.Number("--sun-azimuth", &o.sun_azimuth_deg, "DEG", "the sun given outright: lat-long azimuth (longitude)");
  bool no_export = false, no_report = false, quiet = false, json = false, no_inversion = false;
  cl.Flag("--no-weather-inversion", &no_inversion,
          "partly cloudy: keep the cloud statistics fit's weather map (clouds where its noise puts them)");
  cl.Text("--weather-map", &o.weather_map, "W.exr",
          "partly cloudy: the clouds' shapes given (RGB EXR: coverage, precipitation, type) and held; the lighting is "
          "fitted on them");
  cl.Flag("--no-export", &no_export, "do not write DIR/game (the game tables)");
  cl.Flag("--no-report", &no_report, "do not write the HTML reports");
  cl.Flag("--quiet", &quiet, "no progress lines");
  cl.Flag("--json", &json, "print the summary as JSON on stdout");
  cl.Parse(argc, argv);
  o.export_tables = !no_export;
  o.invert_weather = !no_inversion;
  o.report = !no_report;
  o.verbose = !quiet;
  o.log = [](const std::string& line) { Log("calibrate", FieldsAsFlags(line, kFlags)); };
  if (o.photos.empty()) throw Error("calibrate: --photo P.exr|P.hdr|FOLDER is required (repeat it for several photos)");
  if (o.out_dir.empty()) throw Error("calibrate: --out DIR is required");
  std::string why;
  if (!o.IsValid(&why)) throw Error(FieldsAsFlags(why, kFlags));
  return o;
}

int RunCalibrate(int argc, char** argv) {
  return RunVerb("calibrate", WantsJson(argc, argv), [&]() { return RunCalibrateImpl(ParseCalibrateArgs(argc, argv)); });
}

}  // namespace skycal::cli
