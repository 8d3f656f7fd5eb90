#include "compare_verb.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "command_line.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

nlohmann::json BandsJson(const std::vector<appearance::BandStats>& bands) {
  nlohmann::json out = nlohmann::json::array();
  for (const appearance::BandStats& b : bands)
    out.push_back({{"elevation_deg", {b.elevation_lo_deg, b.elevation_hi_deg}},
                   {"pixels", b.pixels},
                   {"ln_luminance_q10_q50_q90", {b.ln_y_q10, b.ln_y_q50, b.ln_y_q90}},
                   {"median_ln_r_over_g", b.ln_r_over_g},
                   {"median_ln_b_over_g", b.ln_b_over_g}});
  return out;
}

bool HasTransmittance(const ExrRGB& e) {
  return std::find(e.channels.begin(), e.channels.end(), controllers::kCloudTransmittancePlane) != e.channels.end();
}

// The clouds' shapes against a synthetic photo's truth, when both files carry them.
nlohmann::json CloudLayers(const CompareVerbOptions& o, const ExrRGB& photo, const ExrRGB& game,
                           const std::vector<float>& sky) {
  if (!HasTransmittance(photo) || !HasTransmittance(game)) return nullptr;
  int w = 0, h = 0, gw = 0, gh = 0;
  const std::vector<float> pt = ReadExrChannel(o.photo, controllers::kCloudTransmittancePlane, &w, &h);
  const std::vector<float> gt = ReadExrChannel(o.game, controllers::kCloudTransmittancePlane, &gw, &gh);
  const appearance::CloudLayerAgreement a = appearance::CompareCloudLayers(pt, gt, w, h, sky, o.options, o.game);
  Log("compare", "clouds (both files' cloudTransmittance): opacity RMS " + FormatNumber(a.opacity_rms) +
                     ", IoU " + (a.iou ? FormatNumber(*a.iou) : std::string("none (no cloud in either)")));
  return {{"pixels", a.pixels}, {"opacity_rms", a.opacity_rms}, {"iou", a.iou ? nlohmann::json(*a.iou) : nlohmann::json()}};
}

// The sun of --sun-cone: the game file's `sunDirection` (render and calibrate write it).
std::array<double, 3> GameSun(const CompareVerbOptions& o, const ExrRGB& game) {
  const auto sun = capture::SunDirectionAttribute(game.attributes, o.game);
  if (!sun)
    throw Error(o.game + ": no sunDirection attribute (a V3f, as skycal render and calibrate write it); --sun-cone " +
                FormatNumber(o.sun_cone_deg) + " needs the sun it leaves out");
  return *sun;
}

}  // namespace

nlohmann::json RunCompareImpl(const CompareVerbOptions& o) {
  const ExrRGB photo_file = ReadExrRGB(o.photo), game_file = ReadExrRGB(o.game);
  const ImageRGB& photo = photo_file.image;
  ImageRGB game = game_file.image;
  for (float& v : game.pixels) v = static_cast<float>(v * o.exposure);
  std::vector<float> sky;
  if (!o.mask.empty()) {
    const ImageRGB m = ReadExrRGB(o.mask).image;
    if (m.width != photo.width || m.height != photo.height)
      throw Error(o.mask + ": " + std::to_string(m.width) + " x " + std::to_string(m.height) +
                  " pixels, expected the size of " + o.photo + " (" + std::to_string(photo.width) + " x " +
                  std::to_string(photo.height) + ")");
    sky.resize(static_cast<size_t>(m.width) * m.height);
    for (size_t i = 0; i < sky.size(); ++i) sky[i] = m.pixels[3 * i];
  }
  if (o.sun_cone_deg > 0.0)
    sky = appearance::WithoutSunCone(sky, photo.width, photo.height, GameSun(o, game_file), o.sun_cone_deg);
  const appearance::Comparison c = appearance::Compare(photo, game, sky, o.options, o.photo, o.game);
  Log("compare", o.game + " against " + o.photo + ": per-pixel log RMSE " + FormatNumber(c.per_pixel_log_rmse) +
                     ", appearance error " + FormatNumber(c.appearance_error) + " (" + std::to_string(c.bands_compared) +
                     " elevation bands, " + std::to_string(c.sky_pixels) + " sky pixels)");
  return {{"photo", o.photo},
          {"game", o.game},
          {"mask", o.mask.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.mask)},
          {"exposure", o.exposure},
          {"sun_cone_deg", o.sun_cone_deg},
          {"sky_pixels", c.sky_pixels},
          {"per_pixel_log_rmse", c.per_pixel_log_rmse},
          {"appearance_error", c.appearance_error},
          {"band_deg", o.options.band_deg},
          {"min_elevation_deg", o.options.min_elevation_deg},
          {"photo_bands", BandsJson(c.photo)},
          {"game_bands", BandsJson(c.game)},
          {"clouds", CloudLayers(o, photo_file, game_file, sky)}};
}

CompareVerbOptions ParseCompareArgs(int argc, char** argv) {
  VerbCommandLine cl("compare", "skycal compare: the game's image of a sky against the photo (log RMSE, appearance)",
                     "  skycal compare --photo P.exr --game G.exr [--mask MASK.exr] [--exposure K] [--band DEG]\n"
                     "                 [--min-elevation DEG] [--sun-cone DEG] [--json]",
                     "Per-pixel log RMSE (solid-angle weighted, over the sky pixels and channels) and the\n"
                     "appearance error (per elevation band: 10/50/90% quantiles of ln luminance, medians of\n"
                     "ln R/G and ln B/G; RMS of the differences), which does not depend on where clouds sit.\n"
                     "When both files carry cloudTransmittance (skycal render --clouds, calibrate's render.exr, a\n"
                     "synthetic photo's truth): where the clouds sit, opacity RMS and cloud-mask IoU (T < 0.5).\n"
                     "docs/fitting.md \"Judging a calibration\".");
  CompareVerbOptions o;
  cl.Text("--photo", &o.photo, "P.exr", "the photograph (lat-long EXR)");
  cl.Text("--game", &o.game, "G.exr", "the game's image of it, same size (e.g. skycal render --clouds)");
  cl.Text("--mask", &o.mask, "MASK.exr", "sky mask, same size (R > 0.5 is sky; e.g. skycal mask)");
  cl.Number("--exposure", &o.exposure, "K",
            "multiply the game image by K first: a fit's exposure (fit.json references[].exposure) takes\n"
            "the preset's model units to the photo's (default 1)");
  cl.Number("--band", &o.options.band_deg, "DEG", "elevation band width (default 10)");
  cl.Number("--min-elevation", &o.options.min_elevation_deg, "DEG", "pixels below are left out (default 0)");
  cl.Number("--sun-cone", &o.sun_cone_deg, "DEG",
            "leave out the pixels within DEG of the game file's sunDirection (default 0): calibrate's\n"
            "comparison is --mask mask.exr --sun-cone fit.json's calibration.game_sun_cone_deg");
  bool json = false;
  cl.Flag("--json", &json, "print the result as JSON on stdout");
  cl.Parse(argc, argv);
  if (o.photo.empty()) throw Error("compare: --photo P.exr is required");
  if (o.game.empty()) throw Error("compare: --game G.exr is required");
  if (!(o.sun_cone_deg >= 0.0 && o.sun_cone_deg <= 45.0))
    throw Error("--sun-cone " + FormatNumber(o.sun_cone_deg) + ": expected degrees in [0, 45]");
  if (!(o.exposure > 0.0) || !std::isfinite(o.exposure))
    throw Error("--exposure " + FormatNumber(o.exposure) + ": expected a finite factor > 0");
  // The library names its Options fields; the user typed these flags.
  static const FieldFlag kFlags[] = {{"Options::band_deg", "--band"}, {"Options::min_elevation_deg", "--min-elevation"}};
  if (const std::string why = o.options.IsValid(); !why.empty()) throw Error(FieldsAsFlags(why, kFlags));
  return o;
}

int RunCompare(int argc, char** argv) {
  return RunVerb("compare", WantsJson(argc, argv), [&]() { return RunCompareImpl(ParseCompareArgs(argc, argv)); });
}

}  // namespace skycal::cli
