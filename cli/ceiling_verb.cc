#include "ceiling_verb.h"

#include <iostream>

#include "args.h"
#include "skycal/core/error.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/reference.h"
#include "skycal/render/preset.h"
#include "render_verb.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

constexpr const char* kHelp = R"(skycal ceiling: the model's best possible fit of a reference (rel RMSE)

  skycal ceiling --reference R.exr [--init PRESET.json] [--model ffxv|ffxv-iso]
                 [--sun-cone DEG] [--mask MASK.exr] [--json]

  --reference R.exr   lat-long reference frame (its sunDirection attribute gives the sun)
  --init PRESET.json  LUT grid and overcast weight (default: the bundled default_clear preset)
  --model NAME        ffxv-iso (default, as fit) or ffxv
  --sun-cone DEG      pixels within this angle of the sun are left out (default 3, as fit)
  --mask MASK.exr     user mask, as fit (R < 0.5 excludes a pixel)
  --json              print the result as JSON on stdout

Prints the LUT ceiling (tied rows, the fit's grid: rel RMSE and its g) and the per-row
ceiling (one value per table, image row and channel), at the fit's finest level (<= 512 wide).
)";

}  // namespace

nlohmann::json RunCeilingImpl(const CeilingVerbOptions& o) {
  if (o.reference.empty()) throw Error("ceiling: --reference R.exr is required");
  const std::string init_path = o.init_preset.empty() ? DefaultPresetPath() : o.init_preset;
  const render::Preset init = render::LoadPreset(init_path);
  const fit::Reference ref = fit::LoadReference(o.reference, o.fit);
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

int RunCeiling(int argc, char** argv) {
  if (WantsHelp(argc, argv)) {
    std::cout << kHelp;
    return 0;
  }
  return RunVerb("ceiling", WantsJson(argc, argv), [&]() {
    Args a(argc, argv, {"reference", "init", "model", "sun-cone", "mask"}, {"json"});
    CeilingVerbOptions o;
    o.reference = a.Value("reference").value_or("");
    o.init_preset = a.Value("init").value_or("");
    if (auto m = a.Value("model")) o.fit.variant = render::ParseModelVariant(*m, "--model");
    if (auto v = a.Number("sun-cone")) o.fit.sun_cone_deg = *v;
    o.fit.mask_path = a.Value("mask").value_or("");
    o.fit.verbose = false;
    std::string why;
    if (!o.fit.IsValid(&why)) throw Error(why);
    return RunCeilingImpl(o);
  });
}

}  // namespace skycal::cli
