// Suite `fit`: one sky fitted from the bundled default preset (where a user starts,
// docs/benchmarks.md) on clear skies the preset was not built from (CIE general skies,
// another atmosphere's bake) and the CIE sky again with a building and a cloud, 256x128.
// Grid: linear start on/off x robust loss x backend x the Ceres polish (a skip decision of
// the linear start) x pyramid levels (with the other defaults) x Jacobians (analytic, or central differences: the baseline, run only
// on the Ceres path with the CPU backend and Cauchy, as bench_fit does, since elsewhere it
// changes nothing or costs minutes). Time: the fits of all references of the case, median
// of repeats; error: their mean rel RMSE (fit::CompareToReference) against the clean
// reference image, the truth.
#include <cmath>
#include <map>
#include <memory>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

constexpr int kWidth = 256;

// What the fit sees and the clean sky its error is measured against (the same frame but for
// the outlier reference).
struct FitReference {
  fit::Reference seen, truth;
};

// The CIE 12 frame with what real photographs have: a dark building along the horizon
// (elevation < 12 deg over 70 deg of azimuth, 0.3x) and a bright cloud (elevation 35-55 deg
// over 40 deg of azimuth, 2.5x), ~6% of the upper hemisphere's pixels.
void WriteWithOutliers(const std::string& clean, const std::string& path) {
  capture::LatLongFrame f = capture::ReadLatLongFrame(clean);
  ImageRGB& im = f.radiance;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const double el = latlong::Latitude(y, im.height) * 180.0 / M_PI, az = latlong::Longitude(x, im.width) * 180.0 / M_PI;
      const double k = el > 0.0 && el < 12.0 && az > 100.0 && az < 170.0 ? 0.3 : el > 35.0 && el < 55.0 && az > -140.0 && az < -100.0 ? 2.5 : 1.0;
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = static_cast<float>(im.at(x, y, c) * k);
    }
  capture::WriteLatLongFrame(path, f);
}

std::vector<FitReference> WriteReferences(const SuiteOptions& o, const fit::FitOptions& load) {
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const auto variants = refsky::StandardAtmosphereVariants();
  std::vector<FitReference> refs;
  auto clean = [&](const std::string& path) {
    const fit::Reference r = fit::LoadReference(path, load);
    refs.push_back({r, r});
  };
  const std::string dir = o.scratch.string();
  // A clear CIE sky (type 12: the model class's ~2% floor) and another atmosphere's bake.
  refsky::WriteCieReference(dir + "/fit_cie12_30.exr", types[11], latlong::DirectionFromElevationAzimuthDeg(30.0, 20.0), kWidth);
  clean(dir + "/fit_cie12_30.exr");
  WriteWithOutliers(dir + "/fit_cie12_30.exr", dir + "/fit_cie12_30_outliers.exr");
  refs.push_back({fit::LoadReference(dir + "/fit_cie12_30_outliers.exr", load), refs.back().truth});
  refsky::WriteModelReference(dir + "/fit_bake1_45.exr", refsky::BakeVariant(variants[1]),
                              latlong::DirectionFromElevationAzimuthDeg(45.0, -70.0), kWidth);
  clean(dir + "/fit_bake1_45.exr");
  if (!o.quick) {
    refsky::WriteCieReference(dir + "/fit_cie3_60.exr", types[2], latlong::DirectionFromElevationAzimuthDeg(60.0, 20.0), kWidth);
    clean(dir + "/fit_cie3_60.exr");
    refsky::WriteModelReference(dir + "/fit_bake2_10.exr", refsky::BakeVariant(variants[2]),
                                latlong::DirectionFromElevationAzimuthDeg(10.0, -70.0), kWidth);
    clean(dir + "/fit_bake2_10.exr");
  }
  return refs;
}

}  // namespace

namespace {

// The case's fit options: base with the grid's start, loss, backend, polish, levels and
// Jacobians.
fit::FitOptions CaseFitOptions(const fit::FitOptions& base, const Settings& settings) {
  fit::FitOptions f = base;
  f.linear_start = Get(settings, "linear_start") == "on";
  const std::string& loss = Get(settings, "loss");
  f.loss = loss == "cauchy" ? fit::RobustLoss::kCauchy : loss == "huber" ? fit::RobustLoss::kHuber : fit::RobustLoss::kNone;
  f.backend = render::ParseBackend(Get(settings, "backend"), "backend");
  f.polish = Get(settings, "polish") == "on";
  if (Get(settings, "pyramid") != "auto") {
    f.pyramid_widths.clear();
    for (const std::string& w : {std::string("128"), std::string("256")})
      if (Get(settings, "pyramid").find(w) != std::string::npos) f.pyramid_widths.push_back(std::stoi(w));
  }
  if (Get(settings, "jacobian") == "numeric") {
    f.numeric_derivatives = true;
    f.pyramid_widths = {kWidth};  // bench_fit's baseline: one level, more iterations
    f.max_iterations_per_level = 200;
  }
  return f;
}

}  // namespace

Suite FitSuite() {
  Suite s;
  s.name = "fit";
  s.summary = "one-sky fit from the bundled preset, 256x128: start x loss x backend x polish x Jacobians x levels";
  s.error_metric = "mean rel RMSE of the fitted sky vs the clean reference";
  s.error_axis = "mean rel RMSE, fit vs the clean sky";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    // Defaults: fit::FitOptions (linear start, Cauchy, vulkan, analytic).
    grid.axes = {{"linear_start", {"on", "off"}, "on"},
                 {"loss", {"cauchy", "huber", "none"}, "cauchy"},
                 {"backend", {"vulkan", "cpu"}, "vulkan"},
                 {"polish", {"off", "on"}, "off"},
                 {"jacobian", {"analytic", "numeric"}, "analytic"},
                 // Coarse-to-fine level widths: the default (64,128,256 at this size), the finest only, the
                 // finest two.
                 {"pyramid", {"auto", "256", "128,256"}, "auto"}};
    grid.skip = [](const Settings& st) -> std::string {
      if (Get(st, "pyramid") != "auto" &&
          (Get(st, "loss") != "cauchy" || Get(st, "backend") != "vulkan" || Get(st, "polish") != "off" ||
           Get(st, "jacobian") != "analytic"))
        return "pyramid levels: measured with either start and the other defaults only";
      // The polish is a skip decision of the linear start (forced by --polish); the Ceres
      // path always runs Ceres.
      if (Get(st, "polish") == "on" && Get(st, "linear_start") == "off") return "the Ceres path has no polish to skip";
      if (Get(st, "jacobian") != "numeric") return "";
      if (Get(st, "linear_start") == "on") return "the linear start solves the LUT linearly: no Ceres Jacobians to compare";
      if (Get(st, "backend") != "cpu" || Get(st, "loss") != "cauchy" || Get(st, "polish") == "on")
        return "numeric baseline: cpu + Cauchy only";
      return "";
    };
    fit::FitOptions base;
    base.verbose = false;
    const std::vector<FitReference> refs = WriteReferences(o, base);
    const render::Preset start = render::LoadPreset(DefaultPresetPath());
    auto renderers = SkyRenderersByBackend();
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    return RunGrid("fit", grid, o, [&](CaseResult& c) {
      const fit::FitOptions f = CaseFitOptions(base, c.settings);
      render::SkyRenderer& r = *renderers.at(Get(c.settings, "backend"));
      std::vector<fit::FitResult> results(refs.size());
      // The numeric baseline takes seconds per fit: no warm-up, one run.
      const bool slow = f.numeric_derivatives;
      c.time = Measure(
          [&] {
            for (size_t i = 0; i < refs.size(); ++i) results[i] = fit::FitSky({refs[i].seen}, start, f, r);
          },
          slow ? 0 : o.warmup, slow ? 1 : repeats);
      double sum = 0.0;
      bool finite = true;
      nlohmann::json per = nlohmann::json::array();
      int iterations = 0;
      for (size_t i = 0; i < refs.size(); ++i) {
        // Against the clean sky: a fit that follows the outliers is worse, not better.
        const double e = fit::CompareToReference(refs[i].truth, results[i].references.at(0).rendered).rel_rmse;
        finite = finite && std::isfinite(e) && std::isfinite(results[i].preset.haziness_g);
        sum += e;
        iterations += results[i].iterations;
        per.push_back({{"reference", refs[i].seen.name}, {"rel_rmse", e}, {"haziness_g", results[i].preset.haziness_g},
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
