// Suite `fit-clouds`: the cloud-lighting fit with known shapes (`skycal fit --clouds on
// --cloud-preset datasets/presets/default_cloudy.json`: controllers::RunSkyCloudFit, the fit
// controller's own stage, without its file writes) on a synthetic cloudy reference whose lighting is known.
// Truth: another atmosphere's bake (the standard variants' second) under the bundled cloudy
// preset's shapes (weather map, noise seed 1, wind time 0) with six lighting parameters
// moved off the preset's -- extinction 0.05 -> 0.056 /m, scattering_albedo 0.99 -> 0.97,
// phase_g2 0.9 -> 0.86, ms_a 0.5 -> 0.56, ms_b 0.5 -> 0.45, ms_c 0.5 -> 0.54 -- rendered by
// `skycal render --clouds` (controllers::WriteGameRender, Vulkan), sun 30 deg. The fit starts from the
// bundled cloudy preset's lighting (what a user passes). Grid: FitCloudsGrid
// (fit_suite_grids.h) x backend (the cloud values: Vulkan, or the double CPU model, at the
// defaults only). Time: the joint sky + cloud fit, median of repeats; error: RMS over the 14
// lighting parameters of |fitted / truth - 1| (a held parameter keeps its start, so a moved
// one that the pixels cannot separate counts its whole offset). `extra`: the worst
// parameter, each parameter's fitted value and held flag, the cloud pixels' log RMSE, the
// solve's stages.
#include <cmath>
#include <filesystem>
#include <map>

#include "skycal/bench/fit_suite_grids.h"
#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/controllers/fit_clouds.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

constexpr double kSunElevation = 30.0, kSunAzimuth = 40.0;  // deg

// The lighting the reference is rendered with: the bundled section's, six parameters moved.
const std::map<std::string, double>& TruthLighting() {
  static const std::map<std::string, double> m = {{"extinction", 0.056}, {"scattering_albedo", 0.97},
                                                  {"phase_g2", 0.86},    {"ms_a", 0.56},
                                                  {"ms_b", 0.45},        {"ms_c", 0.54}};
  return m;
}

// Writes the truth preset (another atmosphere + the moved lighting; its weather map copied
// beside it) and returns its path and lighting.
std::string WriteTruthPreset(const std::filesystem::path& dir, cloudfit::CloudLighting* lighting) {
  const std::string cloudy = controllers::DefaultCloudyPresetPath();
  const render::Preset bundled = render::LoadPreset(cloudy);
  clouds::CloudParams params = clouds::ParseCloudSectionText(bundled.clouds_json, cloudy);
  *lighting = cloudfit::GetCloudLighting(params);
  for (const auto& [name, value] : TruthLighting()) (*lighting)[cloudfit::CloudLightingIndex(name)] = value;
  cloudfit::SetCloudLighting(*lighting, &params);
  const std::filesystem::path weather = std::filesystem::path(cloudy).parent_path() / params.weather_map;
  params.weather_map = "fit_clouds_truth.weather.exr";
  std::filesystem::copy_file(weather, dir / params.weather_map, std::filesystem::copy_options::overwrite_existing);
  render::Preset truth = refsky::BakeVariant(refsky::StandardAtmosphereVariants().at(1));
  truth.clouds_json = clouds::CloudSectionToJson(params).dump();
  const std::string path = (dir / "fit_clouds_truth.json").string();
  render::SavePreset(truth, path);
  return path;
}

}  // namespace

Grid FitCloudsGrid(bool quick) {
  Grid grid;
  const std::vector<std::string> sizes =
      // Not 64x32 in --quick: its few large pixels made the Jet Jacobians 5x slower than at
      // 128x64 (98 s against 19 s for 256 samples, bench/results/fit-studies-quick).
      quick ? std::vector<std::string>{"128x64"} : std::vector<std::string>{"128x64", "256x128"};
  const std::vector<std::string> samples =
      quick ? std::vector<std::string>{"64", "256"} : std::vector<std::string>{"64", "256", "1024"};
  // Defaults: fit --clouds on from the bundled clear preset, --cloud-samples 256, vulkan.
  grid.axes = {{"sky_start", {"bundled", "truth"}, "bundled"},
               {"backend", {"vulkan", "cpu"}, "vulkan"},
               {"size", sizes, sizes.back()},
               {"samples", samples, "256"}};
  const std::string default_size = sizes.back();
  grid.skip = [default_size](const Settings& st) -> std::string {
    const bool at_defaults = Get(st, "size") == default_size && Get(st, "samples") == "256";
    if (Get(st, "sky_start") == "truth" && (!at_defaults || Get(st, "backend") != "vulkan"))
      return "the truth's sky start: measured at the defaults only";
    if (Get(st, "backend") == "cpu" && !at_defaults) return "the CPU cloud values: measured at the default size and samples";
    return "";
  };
  return grid;
}

namespace {

// The fitted cloud lighting against the truth: error (RMS of |fitted / truth - 1| over the
// parameters), outcome and extra (per parameter, the stages' times) into c.
void ScoreCloudLighting(CaseResult& c, const cloudfit::SkyCloudFit& r, const cloudfit::CloudLighting& truth) {
  const cloudfit::CloudLighting fitted = cloudfit::GetCloudLighting(r.clouds.fitted_params);
  double sum = 0.0, worst = 0.0;
  std::string worst_name;
  nlohmann::json params = nlohmann::json::object();
  for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
    const double e = std::abs(fitted[k] / truth[k] - 1.0);
    sum += e * e;
    if (!(e <= worst)) {
      worst = e;
      worst_name = cloudfit::CloudLightingNames()[k];
    }
    const bool held = k < static_cast<int>(r.clouds.parameters.size()) && r.clouds.parameters[k].held;
    params[cloudfit::CloudLightingNames()[k]] = {{"truth", truth[k]}, {"fitted", fitted[k]}, {"held", held}};
  }
  c.error = std::sqrt(sum / cloudfit::kCloudLightingParameters);
  c.converged = r.clouds.fitted && std::isfinite(c.error);
  if (!std::isfinite(c.error)) {
    c.outcome = Outcome::kNonFinite;
    c.message = "a fitted cloud lighting parameter is non-finite";
  }
  c.extra = {{"worst_parameter", worst_name},
             {"worst_rel_error", worst},
             {"parameters", params},
             {"cloud_pixels", r.clouds.cloud_pixels},
             {"cloud_log_rmse_initial", r.clouds.cloud_initial.log_rmse},
             {"cloud_log_rmse_final", r.clouds.cloud_final.log_rmse},
             {"sky_rel_rmse", r.sky.references.at(0).errors.rel_rmse},
             {"stages_s", {{"cloud_renders", r.clouds.render_time_s}, {"jacobians", r.clouds.jacobian_time_s},
                           {"conditioning", r.clouds.conditioning_time_s}, {"cloud_solve", r.clouds.time_s}}},
             {"termination", r.clouds.termination},
             {"iterations", r.clouds.iterations},
             {"jacobian_evaluations", r.clouds.jacobians},
             {"cloud_renders", r.clouds.renders}};
}

}  // namespace

Suite FitCloudsSuite() {
  Suite s;
  s.name = "fit-clouds";
  s.summary = "fit --clouds on (known shapes) of a cloudy reference with six lighting parameters moved: sky start x "
              "backend x size x cloud samples";
  s.error_metric = "RMS over the 14 cloud lighting parameters of |fitted / truth - 1|";
  s.error_axis = "cloud lighting parameters' RMS rel. error";
  s.run = [](const SuiteOptions& o) {
    const Grid grid = FitCloudsGrid(o.quick);
    cloudfit::CloudLighting truth{};
    const std::string truth_preset = WriteTruthPreset(o.scratch, &truth);
    std::map<std::string, std::string> refs;
    for (const std::string& size : grid.axes[2].values) {
      controllers::GameRenderFileOptions ro;
      ro.render.preset_path = truth_preset;
      ro.render.sun_dir = latlong::DirectionFromElevationAzimuthDeg(kSunElevation, kSunAzimuth);
      ro.render.width = std::stoi(size.substr(0, size.find('x')));
      ro.render.height = ro.render.width / 2;
      ro.render.clouds.enabled = true;
      ro.out_exr = (o.scratch / ("fit_clouds_" + size + ".exr")).string();
      ro.render.verbose = o.verb_logs;
      controllers::WriteGameRender(ro);
      refs[size] = ro.out_exr;
    }
    controllers::FitCloudOptions shapes_options;
    shapes_options.mode = "on";
    shapes_options.preset = controllers::DefaultCloudyPresetPath();
    const std::unique_ptr<controllers::LoadedCloudShapes> shapes = controllers::LoadFitCloudShapes(shapes_options);
    const render::Preset bundled = render::LoadPreset(DefaultPresetPath());
    const render::Preset truth_sky = render::LoadPreset(truth_preset);
    auto renderers = SkyRenderersByBackend();
    const int repeats = o.Repeats(1);  // seconds per fit: one timed run after the warm-up
    return RunGrid("fit-clouds", grid, o, [&](CaseResult& c) {
      const bool from_truth = Get(c.settings, "sky_start") == "truth";
      fit::FitOptions f;
      f.verbose = o.verb_logs;  // the fit's and its clouds' progress lines: --verb-logs only
      f.absolute = from_truth;  // the truth's sky is in the reference's units
      f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
      controllers::FitCloudOptions co = shapes_options;
      co.samples = std::stoi(Get(c.settings, "samples"));
      const std::vector<fit::Reference> ref = {fit::LoadReference(refs.at(Get(c.settings, "size")), f)};
      cloudfit::SkyCloudFit r;
      c.time = Measure(
          [&] {
            r = controllers::RunSkyCloudFit(co, ref, from_truth ? truth_sky : bundled, f,
                                            *renderers.at(Get(c.settings, "backend")), {}, shapes.get());
          },
          o.quick ? 0 : o.warmup, repeats);
      ScoreCloudLighting(c, r, truth);
    });
  };
  return s;
}

}  // namespace skycal::bench
