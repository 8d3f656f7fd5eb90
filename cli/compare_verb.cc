#include "compare_verb.h"

#include <cmath>

#include "command_line.h"
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

}  // namespace

nlohmann::json RunCompareImpl(const CompareVerbOptions& o) {
  const ImageRGB photo = ReadExrRGB(o.photo).image;
  ImageRGB game = ReadExrRGB(o.game).image;
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
  const appearance::Comparison c = appearance::Compare(photo, game, sky, o.options, o.photo, o.game);
  Log("compare", o.game + " against " + o.photo + ": per-pixel log RMSE " + FormatNumber(c.per_pixel_log_rmse) +
                     ", appearance error " + FormatNumber(c.appearance_error) + " (" + std::to_string(c.bands_compared) +
                     " elevation bands, " + std::to_string(c.sky_pixels) + " sky pixels)");
  return {{"photo", o.photo},
          {"game", o.game},
          {"mask", o.mask.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.mask)},
          {"exposure", o.exposure},
          {"sky_pixels", c.sky_pixels},
          {"per_pixel_log_rmse", c.per_pixel_log_rmse},
          {"appearance_error", c.appearance_error},
          {"band_deg", o.options.band_deg},
          {"min_elevation_deg", o.options.min_elevation_deg},
          {"photo_bands", BandsJson(c.photo)},
          {"game_bands", BandsJson(c.game)}};
}

CompareVerbOptions ParseCompareArgs(int argc, char** argv) {
  VerbCommandLine cl("compare", "skycal compare: the game's image of a sky against the photo (log RMSE, appearance)",
                     "  skycal compare --photo P.exr --game G.exr [--mask MASK.exr] [--exposure K] [--band DEG]\n"
                     "                 [--min-elevation DEG] [--json]",
                     "Per-pixel log RMSE (solid-angle weighted, over the sky pixels and channels) and the\n"
                     "appearance error (per elevation band: 10/50/90% quantiles of ln luminance, medians of\n"
                     "ln R/G and ln B/G; RMS of the differences), which does not depend on where clouds sit.\n"
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
  bool json = false;
  cl.Flag("--json", &json, "print the result as JSON on stdout");
  cl.Parse(argc, argv);
  if (o.photo.empty()) throw Error("compare: --photo P.exr is required");
  if (o.game.empty()) throw Error("compare: --game G.exr is required");
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
