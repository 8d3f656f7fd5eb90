// Suite `fit-cie`: the fit against the 15 CIE standard general skies (CIE S 011 / ISO
// 15469) — references independent of the game's sky model, from clear (types 11-15) to
// overcast (1-5) — fitted one at a time from the bundled default preset, as a user would.
// Grid: model variant (ffxv-iso, the default; ffxv, the talk's two terms) x robust loss x
// backend. Time: all the case's fits, one run each (the sweep is the repetition); error:
// the mean rel RMSE over the skies (fit::CompareToReference), with the worst sky and the
// clear/overcast halves in `extra`. The detailed study (sun elevations 10/30/60, regions,
// the overcast variant) is the fit-cie-study suite (bench/results/cie.md).
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

Suite FitCieSuite() {
  Suite s;
  s.name = "fit-cie";
  s.summary = "one-sky fits of the 15 CIE general skies (sun 30 deg), 256x128 (--quick: 5 skies, 128x64), from the bundled preset: model x loss x backend";
  s.error_metric = "mean rel RMSE over the CIE skies (the fitted sky vs the CIE reference)";
  s.error_axis = "mean rel RMSE over the CIE skies";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    grid.axes = {{"model", {"ffxv-iso", "ffxv"}, "ffxv-iso"},
                 {"loss", {"cauchy", "huber"}, "cauchy"},
                 {"backend", {"vulkan", "cpu"}, "vulkan"}};
    const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
    // --quick: every third type (1, 4, 7, 10, 13: overcast to clear).
    fit::FitOptions base;
    base.verbose = false;
    const int width = o.quick ? 128 : 256;
    std::vector<fit::Reference> refs;
    std::vector<int> type_numbers;
    for (size_t t = 0; t < types.size(); t += o.quick ? 3 : 1) {
      const std::string path = (o.scratch / ("cie" + std::to_string(t + 1) + ".exr")).string();
      refsky::WriteCieReference(path, types[t], latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0), width);
      refs.push_back(fit::LoadReference(path, base));
      type_numbers.push_back(static_cast<int>(t + 1));
    }
    const render::Preset start = render::LoadPreset(DefaultPresetPath());
    auto renderers = SkyRenderersByBackend();
    return RunGrid("fit-cie", grid, o, [&](CaseResult& c) {
      fit::FitOptions f = base;
      f.variant = render::ParseModelVariant(Get(c.settings, "model"), "model");
      f.loss = Get(c.settings, "loss") == "cauchy" ? fit::RobustLoss::kCauchy : fit::RobustLoss::kHuber;
      f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
      std::vector<fit::FitResult> results(refs.size());
      // One run of the whole sweep, no warm-up: 15 fits already average the noise.
      c.time = Measure(
          [&] {
            for (size_t i = 0; i < refs.size(); ++i)
              results[i] = fit::FitSky({refs[i]}, start, f, *renderers.at(Get(c.settings, "backend")));
          },
          0, 1);
      double sum = 0.0, worst = 0.0, overcast = 0.0, clear = 0.0;
      int n_overcast = 0, n_clear = 0, worst_type = 0;
      bool finite = true;
      for (size_t i = 0; i < refs.size(); ++i) {
        const double e = fit::CompareToReference(refs[i], results[i].references.at(0).rendered).rel_rmse;
        finite = finite && std::isfinite(e);
        sum += e;
        if (e > worst) worst = e, worst_type = type_numbers[i];
        if (type_numbers[i] <= 5) overcast += e, ++n_overcast;
        if (type_numbers[i] >= 11) clear += e, ++n_clear;
      }
      c.error = sum / refs.size();
      c.converged = finite;
      if (!finite) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite fit error";
      }
      c.extra = {{"skies", refs.size()},
                 {"worst_rel_rmse", worst},
                 {"worst_type", worst_type},
                 {"overcast_types_1_5_mean", n_overcast ? overcast / n_overcast : NAN},
                 {"clear_types_11_15_mean", n_clear ? clear / n_clear : NAN},
                 {"ms_per_fit", c.time.median_ms / refs.size()}};
    });
  };
  return s;
}

}  // namespace skycal::bench
