#include "fit_option_args.h"

#include <cmath>
#include <cstdlib>

#include "option_values.h"
#include "skycal/controllers/fit_controller.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {

void RegisterFitOptionArgs(VerbCommandLine& cl, FitOptionArgs* a, fit::FitOptions* f, std::string* init_preset) {
  cl.Text("--model", &a->model, "NAME", "ffxv-iso (default: + isotropic LUT) or ffxv (the talk's two terms)");
  cl.Text("--backend", &a->backend, "NAME", "vulkan (default: the objective renders through the compute shaders) or cpu");
  cl.Text("--mask", &f->mask_path, "MASK.exr", "user mask, same size as the references: R < 0.5 excludes a pixel");
  cl.Text("--init", init_preset, "PRESET.json", "starting preset (default: the bundled default_clear preset)");
  cl.Flag("--absolute", &f->absolute, "references are calibrated (cd/m^2): the exposure is not fitted");
  cl.Number("--sun-cone", &f->sun_cone_deg, "DEG", "mask this cone around the sun (default 3)");
  cl.Number("--clip-fraction", &f->clip_fraction, "F",
            "with a clipping plateau in a reference, pixels >= F x the clip level are masked (default 0.98)");
  cl.Text("--loss", &a->loss, "NAME", "cauchy (default), huber or none: robust loss on log residuals");
  cl.Number("--loss-scale", &f->loss_scale, "S",
            "floor of the robust loss scale, natural-log units (default 0.05, ~5%);\n"
            "the fit widens it to 2.385 x the MAD-sigma of its least-squares residuals");
  cl.Flag("--no-linear-start", &a->no_linear_start,
          "skip the linear start (variable projection over g): coarse-to-fine\n"
          "Ceres from the initial preset (the slower path of earlier versions)");
  cl.Integer("--linear-width", &f->linear_width, -1e9, 1e9, "expected an integer width", "W",
             "level width of the linear start's g search (default 128)");
  cl.Flag("--polish", &f->polish,
          "always polish the linear start with Ceres through the backend\n"
          "(it runs anyway with probe samples or a failed render check)");
  cl.Text("--pyramid", &a->pyramid, "W1,W2,...", "coarse-to-fine level widths (default 64,128,... up to min(width, 512))");
  cl.Integer("--max-iterations", &f->max_iterations_per_level, -1e9, 1e9, "expected an integer", "N",
             "per pyramid level (default 50)");
  cl.Number("--smoothness", &f->smoothness, "L", "second-difference prior on the LUT change along sun zenith (default 1e-6)");
  cl.Number("--prior-weight", &f->prior_weight, "L", "pull toward the initial LUT (default 1e-8)");
  cl.Number("--unseen-profile", &f->unseen_profile, "L",
            "smoothness of what the game draws at the azimuths a masked horizon hides,\n"
            "across the LUT columns (default 1e-4, 0: off)");
  cl.Flag("--no-haziness", &a->no_haziness, "hold g at its initial value");
  cl.Flag("--numeric-derivatives", &f->numeric_derivatives, "central-difference Jacobians (the benchmark's baseline)");
  cl.Flag("--quiet", &a->quiet, "no per-iteration progress");
  cl.Number("--probe-weight", &f->probe_weight, "L",
            "the probe residuals of a reference weigh L times its sky pixels (default 0.1)");
  cl.Integer("--probe-quadrature", &f->probe_quadrature_width, -1e9, 1e9, "expected an integer width", "W",
             "lat-long width of the sky irradiance quadrature (default 128)");
  cl.Flag("--no-ground-albedo", &a->no_ground_albedo, "hold the ground albedo at the initial preset's value");
}

std::string WithFitFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"FitOptions::sun_cone_deg", "--sun-cone"},
                                     {"FitOptions::clip_fraction", "--clip-fraction"},
                                     {"FitOptions::loss_scale", "--loss-scale"},
                                     {"FitOptions::linear_width", "--linear-width"},
                                     {"FitOptions::max_iterations_per_level", "--max-iterations"},
                                     {"FitOptions::smoothness", "--smoothness"},
                                     {"FitOptions::prior_weight", "--prior-weight"},
                                     {"FitOptions::unseen_profile", "--unseen-profile"},
                                     {"FitOptions::pyramid_widths", "--pyramid"},
                                     {"FitOptions::sun_dir", "--sun-dir"},
                                     {"FitOptions::probe_weight", "--probe-weight"},
                                     {"FitOptions::probe_quadrature_width", "--probe-quadrature"},
                                     {"FitOptions::time_of_day_h", "--time"}};
  return FieldsAsFlags(message, kFlags);
}

void ApplyFitOptionArgs(const FitOptionArgs& a, fit::FitOptions* f) {
  if (a.model) f->variant = render::ParseModelVariant(*a.model, "--model");
  if (a.backend) f->backend = render::ParseBackend(*a.backend, "--backend");
  if (a.loss) {
    if (*a.loss == "cauchy") f->loss = fit::RobustLoss::kCauchy;
    else if (*a.loss == "huber") f->loss = fit::RobustLoss::kHuber;
    else if (*a.loss == "none") f->loss = fit::RobustLoss::kNone;
    else throw Error("--loss: unknown loss '" + *a.loss + "' (expected cauchy, huber or none)");
  }
  if (a.pyramid) {
    for (double w : ParseNumberList(*a.pyramid, "--pyramid")) {
      if (w != std::floor(w) || std::abs(w) > 1e9) throw Error("--pyramid: expected integer widths");
      f->pyramid_widths.push_back(static_cast<int>(w));
    }
  }
  f->fit_haziness = !a.no_haziness;
  f->fit_ground_albedo = !a.no_ground_albedo;
  f->linear_start = !a.no_linear_start;
  f->verbose = !a.quiet;
}

nlohmann::json ResolvedFitOptionsJson(const fit::FitOptions& fo) { return controllers::ResolvedFitOptionsJson(fo); }

}  // namespace skycal::cli
