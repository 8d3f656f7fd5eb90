#include "ceiling_verb.h"

#include <iostream>

#include "command_line.h"
#include "finite_output.h"
#include "fit_option_args.h"
#include "skycal/core/error.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/reference.h"
#include "skycal/render/preset.h"
#include "render_verb.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

}  // namespace

nlohmann::json RunCeilingImpl(const CeilingVerbOptions& o) {
  if (o.reference.empty()) throw Error("ceiling: --reference R.exr is required");
  const std::string init_path = o.init_preset.empty() ? DefaultPresetPath() : o.init_preset;
  const render::Preset init = render::LoadPreset(init_path);
  const fit::Reference ref = fit::LoadReference(o.reference, o.fit);
  RequireValidShare(o.reference, ref.counts.sky, ref.counts.sky + ref.counts.invalid + ref.counts.clipped,
                    "fittable sky pixels of those above the horizon outside the sun cone");
  const fit::CeilingResult c = fit::ModelCeiling(ref, init, o.fit);
  Log("ceiling", ref.name + ": LUT ceiling rel RMSE " + std::to_string(100.0 * c.lut_rel_rmse) + "% at g " +
                     std::to_string(c.lut_g) + "; per-row ceiling " + std::to_string(100.0 * c.per_row_rel_rmse) +
                     "% (" + std::to_string(c.width) + " wide, " + std::to_string(c.time_s) + " s)");
  return {{"reference", o.reference},
          {"init", init_path},
          {"model", render::ToString(o.fit.variant)},
          {"width", c.width},
          {"lut_ceiling", {{"rel_rmse", c.lut_rel_rmse}, {"haziness_g", c.lut_g}}},
          {"per_row_ceiling", {{"rel_rmse", c.per_row_rel_rmse}, {"haziness_g", c.per_row_g}}},
          {"time_s", c.time_s}};
}

CeilingVerbOptions ParseCeilingArgs(int argc, char** argv) {
  VerbCommandLine cl("ceiling", "skycal ceiling: the model's best possible fit of a reference (rel RMSE)",
                     "  skycal ceiling --reference R.exr [--init PRESET.json] [--model ffxv|ffxv-iso]\n"
                     "                 [--sun-cone DEG] [--mask MASK.exr] [--json]",
                     "Prints the LUT ceiling (tied rows, the fit's grid: rel RMSE and its g) and the per-row\n"
                     "ceiling (one value per table, image row and channel), at the fit's finest level (<= 512 wide).");
  CeilingVerbOptions o;
  std::optional<std::string> model;
  bool json = false;
  cl.Text("--reference", &o.reference, "R.exr", "lat-long reference frame (its sunDirection attribute gives the sun)");
  cl.Text("--init", &o.init_preset, "PRESET.json", "LUT grid and overcast weight (default: the bundled default_clear preset)");
  cl.Text("--model", &model, "NAME", "ffxv-iso (default, as fit) or ffxv");
  cl.Number("--sun-cone", &o.fit.sun_cone_deg, "DEG", "pixels within this angle of the sun are left out (default 3, as fit)");
  cl.Text("--mask", &o.fit.mask_path, "MASK.exr", "user mask, as fit (R < 0.5 excludes a pixel)");
  cl.Flag("--json", &json, "print the result as JSON on stdout");
  cl.Parse(argc, argv);
  if (model) o.fit.variant = render::ParseModelVariant(*model, "--model");
  o.fit.verbose = false;
  std::string why;
  if (!o.fit.IsValid(&why)) throw Error(WithFitFlags(why));
  return o;
}

int RunCeiling(int argc, char** argv) {
  return RunVerb("ceiling", WantsJson(argc, argv), [&]() { return RunCeilingImpl(ParseCeilingArgs(argc, argv)); });
}

}  // namespace skycal::cli
