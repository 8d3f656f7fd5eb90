// Suite `fit-day`: a clear day fitted as one problem (the LUT shared by every frame, an
// exposure per frame, the smoothness prior along sun zenith) from the bundled default
// preset, on frames baked from an atmosphere the preset was not built from (the standard
// variants' second: other aerosol amount and albedo), sun elevation 4..80 deg over the day.
// Grid: frames per day (3, 6, 12, 24; --quick 3, 6) x backend x the smoothness prior
// (default, off) x path (the linear start; the old coarse-to-fine Ceres path, at the most
// frames only: bench_fit's 24-reference day). Time: the day's whole fit, median of repeats
// (the old path: one run); error: the mean rel RMSE of the fitted frames against their
// references (the truth: noiseless bakes).
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
namespace {

// `n` frames along a day: sun elevation from 4 to 80 deg and back is the shape of a
// summer day; here the rising half at even steps of elevation, azimuth sweeping 100 deg.
std::vector<fit::Reference> WriteDay(const SuiteOptions& o, int n, int width, const fit::FitOptions& load) {
  const auto variants = refsky::StandardAtmosphereVariants();
  const render::Preset truth = refsky::BakeVariant(variants.at(1));
  std::vector<fit::Reference> refs;
  for (int i = 0; i < n; ++i) {
    const double t = n > 1 ? static_cast<double>(i) / (n - 1) : 0.5;
    const double el = 4.0 + 76.0 * t, az = -60.0 + 100.0 * t;
    const std::string path = (o.scratch / ("day" + std::to_string(n) + "_" + std::to_string(i) + ".exr")).string();
    refsky::WriteModelReference(path, truth, latlong::DirectionFromElevationAzimuthDeg(el, az), width);
    refs.push_back(fit::LoadReference(path, load));
  }
  return refs;
}

}  // namespace

Suite FitDaySuite() {
  Suite s;
  s.name = "fit-day";
  s.summary = "a clear day fitted as one problem from the bundled preset: frames x backend x smoothness x path";
  s.error_metric = "mean rel RMSE of the fitted frames vs their references (another atmosphere's bakes)";
  s.error_axis = "mean rel RMSE over the day's frames";
  s.run = [](const SuiteOptions& o) {
    const int width = o.quick ? 128 : 256;
    Grid grid;
    const std::vector<std::string> frames =
        o.quick ? std::vector<std::string>{"3", "6"} : std::vector<std::string>{"3", "6", "12", "24"};
    grid.axes = {{"frames", frames, "6"},
                 {"backend", {"vulkan", "cpu"}, "vulkan"},
                 {"smoothness", {"default", "off"}, "default"},
                 {"path", {"linear-start", "ceres"}, "linear-start"}};
    const std::string most = frames.back();
    grid.skip = [most](const Settings& st) -> std::string {
      if (Get(st, "smoothness") == "off" && Get(st, "frames") != "6") return "the prior's effect: measured at 6 frames only";
      if (Get(st, "path") == "ceres" &&
          (Get(st, "frames") != most || Get(st, "backend") != "vulkan" || Get(st, "smoothness") != "default"))
        return "the old path: at the most frames with the other defaults only";
      return "";
    };
    fit::FitOptions base;
    base.verbose = false;
    std::map<std::string, std::vector<fit::Reference>> days;
    for (const std::string& n : grid.axes[0].values) days[n] = WriteDay(o, std::stoi(n), width, base);
    const render::Preset start = render::LoadPreset(DefaultPresetPath());
    auto renderers = SkyRenderersByBackend();
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    return RunGrid("fit-day", grid, o, [&](CaseResult& c) {
      fit::FitOptions f = base;
      f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
      if (Get(c.settings, "smoothness") == "off") f.smoothness = 0.0;
      f.linear_start = Get(c.settings, "path") == "linear-start";
      const std::vector<fit::Reference>& refs = days.at(Get(c.settings, "frames"));
      fit::FitResult result;
      const bool slow = !f.linear_start;  // tens of seconds: one run, no warm-up
      c.time = Measure([&] { result = fit::FitSky(refs, start, f, *renderers.at(Get(c.settings, "backend"))); },
                       slow ? 0 : o.warmup, slow ? 1 : repeats);
      double sum = 0.0, worst = 0.0;
      bool finite = std::isfinite(result.preset.haziness_g);
      for (size_t i = 0; i < refs.size(); ++i) {
        const double e = fit::CompareToReference(refs[i], result.references.at(i).rendered).rel_rmse;
        finite = finite && std::isfinite(e);
        sum += e;
        worst = std::max(worst, e);
      }
      c.error = sum / refs.size();
      c.converged = finite;
      if (!finite) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite fit error or g";
      }
      c.extra = {{"frames", refs.size()},
                 {"worst_frame_rel_rmse", worst},
                 {"ms_per_frame", c.time.median_ms / refs.size()},
                 {"ceres_iterations", result.iterations},
                 {"linear_start_ms", 1e3 * result.linear_start.time_s()},
                 {"haziness_g", result.preset.haziness_g},
                 {"truth_haziness_g", refsky::StandardAtmosphereVariants().at(1).haziness_g}};
    });
  };
  return s;
}

}  // namespace skycal::bench
