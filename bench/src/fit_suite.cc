// Suite `fit`: one sky fitted from the bundled default preset (where a user starts,
// DESIGN.md section 6) on clear skies the preset was not built from (CIE general skies,
// another atmosphere's bake), 256x128. Grid: linear start on/off x robust loss x backend x
// Jacobians (analytic, or central differences: the baseline, run only on the Ceres path with
// the CPU backend and Cauchy, as bench_fit does, since elsewhere it changes nothing or costs
// minutes). Time: the fits of all references of the case, median of repeats; error: their
// mean rel RMSE (fit::CompareToReference) against the reference image, the truth.
#include <cmath>
#include <map>
#include <memory>

#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

constexpr int kWidth = 256;

std::vector<fit::Reference> WriteReferences(const SuiteOptions& o, const fit::FitOptions& load) {
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const auto variants = refsky::StandardAtmosphereVariants();
  std::vector<fit::Reference> refs;
  const std::string dir = o.scratch.string();
  // A clear CIE sky (type 12: the model class's ~2% floor) and another atmosphere's bake.
  refsky::WriteCieReference(dir + "/fit_cie12_30.exr", types[11], latlong::DirectionFromElevationAzimuthDeg(30.0, 20.0), kWidth);
  refs.push_back(fit::LoadReference(dir + "/fit_cie12_30.exr", load));
  refsky::WriteModelReference(dir + "/fit_bake1_45.exr", refsky::BakeVariant(variants[1]),
                              latlong::DirectionFromElevationAzimuthDeg(45.0, -70.0), kWidth);
  refs.push_back(fit::LoadReference(dir + "/fit_bake1_45.exr", load));
  if (!o.quick) {
    refsky::WriteCieReference(dir + "/fit_cie3_60.exr", types[2], latlong::DirectionFromElevationAzimuthDeg(60.0, 20.0), kWidth);
    refs.push_back(fit::LoadReference(dir + "/fit_cie3_60.exr", load));
    refsky::WriteModelReference(dir + "/fit_bake2_10.exr", refsky::BakeVariant(variants[2]),
                                latlong::DirectionFromElevationAzimuthDeg(10.0, -70.0), kWidth);
    refs.push_back(fit::LoadReference(dir + "/fit_bake2_10.exr", load));
  }
  return refs;
}

}  // namespace

Suite FitSuite() {
  Suite s;
  s.name = "fit";
  s.summary = "one-sky fit from the bundled preset, 256x128: linear start x loss x backend x Jacobians";
  s.error_metric = "mean rel RMSE of the fitted sky vs the reference";
  s.error_axis = "mean rel RMSE, fit vs reference";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    // Defaults: fit::FitOptions (linear start, Cauchy, vulkan, analytic).
    grid.axes = {{"linear_start", {"on", "off"}, "on"},
                 {"loss", {"cauchy", "huber", "none"}, "cauchy"},
                 {"backend", {"vulkan", "cpu"}, "vulkan"},
                 {"jacobian", {"analytic", "numeric"}, "analytic"}};
    grid.skip = [](const Settings& st) -> std::string {
      if (Get(st, "jacobian") != "numeric") return "";
      if (Get(st, "linear_start") == "on") return "the linear start solves the LUT linearly: no Ceres Jacobians to compare";
      if (Get(st, "backend") != "cpu" || Get(st, "loss") != "cauchy") return "numeric baseline: cpu + Cauchy only";
      return "";
    };
    fit::FitOptions base;
    base.verbose = false;
    const std::vector<fit::Reference> refs = WriteReferences(o, base);
    const render::Preset start = render::LoadPreset(DefaultPresetPath());
    std::map<std::string, std::unique_ptr<render::SkyRenderer>> renderers;
    renderers["cpu"] = render::CreateRenderer(render::Backend::kCpu);
    renderers["vulkan"] = render::CreateRenderer(render::Backend::kVulkan);
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    return RunGrid("fit", grid, o, [&](CaseResult& c) {
      fit::FitOptions f = base;
      f.linear_start = Get(c.settings, "linear_start") == "on";
      const std::string& loss = Get(c.settings, "loss");
      f.loss = loss == "cauchy" ? fit::RobustLoss::kCauchy : loss == "huber" ? fit::RobustLoss::kHuber : fit::RobustLoss::kNone;
      f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
      if (Get(c.settings, "jacobian") == "numeric") {
        f.numeric_derivatives = true;
        f.pyramid_widths = {kWidth};  // bench_fit's baseline: one level, more iterations
        f.max_iterations_per_level = 200;
      }
      render::SkyRenderer& r = *renderers.at(Get(c.settings, "backend"));
      std::vector<fit::FitResult> results(refs.size());
      // The numeric baseline takes seconds per fit: no warm-up, one run.
      const bool slow = f.numeric_derivatives;
      c.time = Measure(
          [&] {
            for (size_t i = 0; i < refs.size(); ++i) results[i] = fit::FitSky({refs[i]}, start, f, r);
          },
          slow ? 0 : o.warmup, slow ? 1 : repeats);
      double sum = 0.0;
      bool finite = true;
      nlohmann::json per = nlohmann::json::array();
      int iterations = 0;
      for (size_t i = 0; i < refs.size(); ++i) {
        const double e = results[i].references.at(0).errors.rel_rmse;
        finite = finite && std::isfinite(e) && std::isfinite(results[i].preset.haziness_g);
        sum += e;
        iterations += results[i].iterations;
        per.push_back({{"reference", refs[i].name}, {"rel_rmse", e}, {"haziness_g", results[i].preset.haziness_g},
                       {"termination", results[i].termination}});
      }
      c.error = sum / refs.size();
      c.converged = finite;
      if (!finite) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite fit error or g";
      }
      c.extra = {{"references", per}, {"ceres_iterations", iterations}};
    });
  };
  return s;
}

}  // namespace skycal::bench
