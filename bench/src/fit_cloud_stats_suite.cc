// Suite `fit-cloud-stats`: the unknown-shapes cloud lighting fit (cloudfit/include/skycal/cloudfit/
// cloud_stats.h) over seed pairs — what the bench_cloud_stats program measured
// (bench/results/cloud_stats_seed_pairs*.md), now a suite of `skycal bench`.
//
// Each reference is rendered with noise/weather seeds 1+k/11+k (default_cloudy's lighting,
// sun 25 deg up at azimuth 30); the fit renders with 101+k/211+k (other shapes, the same
// weather statistics) from the truth times (extinction 1.3, g1 0.7, powder 0.7, ambient 1.3)
// for the fitted parameters, the others held at the truth. Pair k = 0 is the known-shapes
// control (model seeds = reference seeds, one model render). Further references of a fit
// use seeds 1+k+10j / 11+k+10j; E > 1 model weather maps use seeds 211+k+1000e; whitening
// draws use weather maps 5000+d; model noise textures 101+k+1000i. Grid: `config`
// (CloudStatsConfig: the configurations the program's results files report, plus
// `default`, the options a photo fit gets). Error: the median |rel error| of the fitted
// parameters over the unknown-shape pairs; `extra` has every pair's row (per-parameter
// truth, start, fitted, rel error; cost, iterations, renders, time, singular values).
// Time: the case's fits, one run (minutes per pair at full size on a 2-core machine).
#include <algorithm>
#include <cmath>
#include <memory>
#include <tuple>

#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/bench/cloud_stats_suite_grids.h"
#include "skycal/core/error.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

namespace {

constexpr double kSunElevationDeg = 25.0, kSunAzimuthDeg = 30.0;
const std::vector<std::string> kFour = {"extinction", "phase_g1", "powder_strength", "ambient_strength"};
const std::vector<std::string> kTwo = {"extinction", "ambient_strength"};
const std::vector<std::string> kAmbient = {"ambient_strength"};
const std::vector<std::string> kAlbedoAmbient = {"scattering_albedo", "ambient_strength"};

// Start: the truth times these factors (clamped into the spec's bounds), fitted parameters only.
const std::vector<std::pair<std::string, double>>& StartFactors() {
  static const std::vector<std::pair<std::string, double>> f = {
      {"extinction", 1.3}, {"phase_g1", 0.7}, {"powder_strength", 0.7}, {"ambient_strength", 1.3},
      {"scattering_albedo", 0.7}};
  return f;
}

const clouds::CloudParamSpec& Spec(const std::string& name) {
  for (const auto& s : clouds::CloudParameterSpecs())
    if (name == s.name) return s;
  throw Error("fit-cloud-stats: no cloud field " + name);
}

std::string Join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& n : v) s += (s.empty() ? "" : ",") + n;
  return s;
}

std::string SignedPct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%+.1f%%", 100.0 * v);
  return b;
}

cloudfit::CloudStatsOptions OptionsFor(const CloudStatsPlan& plan, const CloudStatsConfig& cfg) {
  cloudfit::CloudStatsOptions o;
  const int width = plan.width_override > 0 ? plan.width_override : cfg.width;
  if (width > 0) o.render_width = width, o.render_height = width / 2;
  if (cfg.model_renders > 0) o.model_renders = cfg.model_renders;
  if (cfg.max_iterations > 0) o.max_iterations = cfg.max_iterations;
  if (plan.iteration_cap > 0) o.max_iterations = std::min(o.max_iterations, plan.iteration_cap);
  if (!cfg.fitted.empty()) o.fitted = cfg.fitted;
  o.noise_draws = cfg.noise_draws;
  o.noise_covariance = cfg.covariance;
  return o;
}

// The whitening's description for a case's header (older results have no covariance).
std::string Whitening(const nlohmann::json& x) {
  if (x["noise_draws"].get<int>() == 0 || !x.contains("noise_covariance")) return "";
  return "; covariance " + x["noise_covariance"].get<std::string>() +
         (x["noise_covariance"] == "full" ? " (shrunk toward the diagonal, λ estimated per fit)" : "") +
         ", draws over " +
         (x["draw_noise_textures"].get<int>() > 0 ? std::to_string(x["draw_noise_textures"].get<int>()) + " noise textures"
                                                  : std::string("the model's noise texture")) +
         "; extinction start " + FormatG(x["extinction_start"].get<double>()) + "x the truth";
}

// One seed pair's fit (k = 0: the control) -> its row.
nlohmann::json RunPair(int k, const CloudStatsConfig& cfg, const cloudfit::CloudStatsOptions& options,
                       clouds::CloudRenderer& renderer, const std::string& cache, const SuiteOptions& o) {
  const bool control = k == 0;
  const auto uk = static_cast<uint64_t>(k);
  const CloudStatsSeeds ref_seeds{1 + uk, 11 + uk};
  const CloudStatsSeeds model_seeds = control ? ref_seeds : CloudStatsSeeds{101 + uk, 211 + uk};
  auto scene = MakeCloudStatsScene(SKYCAL_SOURCE_DIR, ref_seeds, model_seeds, kSunElevationDeg, kSunAzimuthDeg, options,
                                   renderer, cache);
  clouds::CloudParams start = scene.truth;
  for (const auto& [name, f] : StartFactors()) {
    if (std::find(options.fitted.begin(), options.fitted.end(), name) == options.fitted.end()) continue;
    const auto& s = Spec(name);
    *s.field(start) = std::clamp(*s.field(scene.truth) * (name == "extinction" ? cfg.extinction_start : f), s.min, s.max);
  }
  cloudfit::CloudStatsScene model{&scene.preset, start, &scene.noise, &scene.weather};
  std::vector<clouds::WeatherMap> ensemble, noise_maps;
  if (!control && cfg.model_maps > 1) {
    ensemble.push_back(scene.weather);
    for (int e = 1; e < cfg.model_maps; ++e)
      ensemble.push_back(CloudStatsWeather(model_seeds.weather + 1000 * e, scene.truth.weather_extent_m));
    for (const auto& w : ensemble) model.weather_ensemble.push_back(&w);
  }
  for (int d = 0; d < options.noise_draws; ++d) noise_maps.push_back(CloudStatsWeather(5000 + d, scene.truth.weather_extent_m));
  for (const auto& w : noise_maps) model.shape_draw_maps.push_back(&w);
  std::vector<clouds::CloudNoise> draw_textures;
  for (int i = 0; i < cfg.draw_noises; ++i)
    draw_textures.push_back(clouds::LoadOrGenerateCloudNoise(7001 + static_cast<uint64_t>(i), cache));
  for (const auto& t : draw_textures) model.shape_draw_noises.push_back(&t);
  std::vector<clouds::CloudNoise> textures;
  if (!control && cfg.model_noises > 1) {
    for (int i = 1; i < cfg.model_noises; ++i)
      textures.push_back(clouds::LoadOrGenerateCloudNoise(model_seeds.noise + 1000 * i, cache));
    model.noise_textures.push_back(&scene.noise);
    for (const auto& t : textures) model.noise_textures.push_back(&t);
  }
  cloudfit::CloudStatsOptions run_options = options;
  if (control) run_options.model_renders = 1;  // the reference's own shapes, at its own wind time
  std::vector<cloudfit::CloudStatsReference> refs = {scene.reference};
  for (int j = 1; j < cfg.references; ++j) {
    const CloudStatsSeeds more{1 + uk + 10 * j, 11 + uk + 10 * j};
    refs.push_back(MakeCloudStatsScene(SKYCAL_SOURCE_DIR, more, model_seeds, kSunElevationDeg, kSunAzimuthDeg, options,
                                       renderer, cache)
                       .reference);
  }
  const cloudfit::CloudStatsResult res = cloudfit::FitCloudStats(refs, model, renderer, run_options);
  nlohmann::json row = {{"control_known_shapes", control},
                        {"reference_seeds", {ref_seeds.noise, ref_seeds.weather}},
                        {"model_seeds", {model_seeds.noise, model_seeds.weather}},
                        {"iterations", res.iterations},
                        {"renders", res.renders},
                        {"residuals", res.residuals},
                        {"time_s", res.time_s},
                        {"initial_cost", res.initial_cost},
                        {"final_cost", res.final_cost},
                        {"singular_values", res.singular_values},
                        {"noise_draws", res.noise_draws},
                        {"median_noise_sd", res.median_noise_sd},
                        {"noise_covariance", res.noise_covariance},
                        {"noise_shrinkage", res.noise_shrinkage},
                        {"termination", res.termination}};
  std::string line = "[cloud-stats seed pairs]   pair " + std::to_string(k) + (control ? " (control)" : "") + ":";
  for (const auto& [name, f] : StartFactors()) {
    clouds::CloudParams fitted = res.params, truth = scene.truth;
    const double t = *Spec(name).field(truth), v = *Spec(name).field(fitted);
    row["parameters"][name] = {
        {"truth", t}, {"start", *Spec(name).field(start)}, {"fitted", v}, {"rel_error", (v - t) / t}};
    line += " " + name + " " + SignedPct((v - t) / t);
  }
  o.Log(line + ", " + FormatG(res.time_s) + " s, " + std::to_string(res.renders) + " renders");
  return row;
}

}  // namespace

CloudStatsPlan FitCloudStatsPlan(bool quick) {
  CloudStatsPlan p;
  // name, width, refs, maps, renders, iterations, fitted, draws, noises, results file, program args
  p.configs = {
      {"default", 0, 1, 1, 0, 0, {}, 0, 1, "", ""},
      {"first-128", 128, 1, 1, 2, 0, kFour, 0, 1, "cloud_stats_seed_pairs", "128"},
      {"3refs-128", 128, 3, 1, 2, 0, kFour, 0, 1, "cloud_stats_seed_pairs_3refs", "128 3"},
      {"first-64", 64, 1, 1, 2, 8, kFour, 0, 1, "cloud_stats_seed_pairs_64", "64 1 1 2 8"},
      {"ensemble", 64, 1, 4, 4, 8, kFour, 0, 1, "cloud_stats_seed_pairs_ensemble", "64 1 4 4 8"},
      {"ensemble-2params", 64, 1, 4, 4, 8, kTwo, 0, 1, "cloud_stats_seed_pairs_ensemble_2params",
       "64 1 4 4 8 extinction,ambient_strength"},
      {"gls", 64, 1, 4, 4, 8, kFour, 24, 1, "cloud_stats_seed_pairs_gls",
       "64 1 4 4 8 extinction,phase_g1,powder_strength,ambient_strength 24"},
      {"gls-2params", 64, 1, 4, 4, 8, kTwo, 24, 1, "cloud_stats_seed_pairs_gls_2params",
       "64 1 4 4 8 extinction,ambient_strength 24"},
      {"gls-2params-3refs", 64, 3, 4, 4, 8, kTwo, 24, 1, "cloud_stats_seed_pairs_gls_2params_3refs",
       "64 3 4 4 8 extinction,ambient_strength 24"},
      {"noises-2params", 64, 1, 4, 4, 8, kTwo, 0, 4, "cloud_stats_seed_pairs_noises_2params",
       "64 1 4 4 8 extinction,ambient_strength 0 4"},
  };
  if (quick) {
    std::vector<CloudStatsConfig> keep;
    for (const auto& c : p.configs)
      if (c.name == "default" || c.name == "gls-2params") keep.push_back(c);
    p.configs = keep;
    p.pairs = 1;
    p.width_override = 64;
    p.iteration_cap = 2;
  }
  Axis axis{"config", {}, "default"};
  for (const auto& c : p.configs) axis.values.push_back(c.name);
  p.grid.axes = {axis};
  return p;
}

CloudStatsPlan FitCloudStatsGlsPlan(bool quick) {
  CloudStatsPlan p;
  // The same 24 whitening draws (weather maps 5000+d, noise textures 7001 + d % 6) for every
  // case: diagonal and full whitening differ only in the covariance.
  auto gls = [](const char* name, std::vector<std::string> fitted, const char* covariance, double extinction_start) {
    CloudStatsConfig c{name, 64, 1, 4, 4, 8, std::move(fitted), 24, 1, "", ""};
    c.covariance = covariance;
    c.draw_noises = 6;
    c.extinction_start = extinction_start;
    return c;
  };
  p.configs = {gls("diag-2params", kTwo, "diagonal", 1.3),         gls("full-2params", kTwo, "full", 1.3),
               gls("diag-2params-low", kTwo, "diagonal", 0.7),     gls("full-2params-low", kTwo, "full", 0.7),
               gls("diag-ambient", kAmbient, "diagonal", 1.3),     gls("full-ambient", kAmbient, "full", 1.3),
               gls("full-albedo-ambient", kAlbedoAmbient, "full", 1.3)};
  // Cheaper settings tried for the recovery test (tests/cloud_stats_test.cc, Regime2*): 2 model
  // renders, 8 draws over 2 noise textures, at most 4 iterations.
  const std::tuple<const char*, std::vector<std::string>, const char*> tests[] = {
      {"test-ambient", kAmbient, "full"},
      {"test-albedo-ambient", kAlbedoAmbient, "full"},
      {"test-diag-ambient", kAmbient, "diagonal"}};
  for (const auto& [name, fitted, covariance] : tests) {
    CloudStatsConfig c = gls(name, fitted, covariance, 1.3);
    c.model_maps = 2;
    c.model_renders = 2;
    c.max_iterations = 4;
    c.noise_draws = 8;
    c.draw_noises = 2;
    p.configs.push_back(c);
  }
  // --quick: the cheaper settings only, 5 pairs each (~2 min). Tried for the recovery test:
  // their spread (worst 73% on ambient) is too wide for a tolerance, so the test runs `diag-ambient`.
  if (quick) p.configs.erase(p.configs.begin(), p.configs.end() - 3);
  // The default: the library's default fitted set (ambient alone) with its best whitening.
  Axis axis{"config", {}, quick ? std::string("test-diag-ambient") : std::string("diag-ambient")};
  for (const auto& c : p.configs) axis.values.push_back(c.name);
  p.grid.axes = {axis};
  return p;
}

const CloudStatsConfig& FindCloudStatsConfig(const CloudStatsPlan& plan, const std::string& name) {
  for (const auto& c : plan.configs)
    if (c.name == name) return c;
  throw Error("fit-cloud-stats: no configuration '" + name + "'");
}

namespace {

// One configuration's section: its settings, a row per pair, the spread per parameter.
std::string SeedPairSection(const CaseResult& c) {
  const auto& x = c.extra;
  std::string md = "\n## " + Get(c.settings, "config") + (c.is_default ? " (the default)" : "") + "\n\n" +
        std::to_string(x["render_width"].get<int>()) + "x" + std::to_string(x["render_width"].get<int>() / 2) +
        " renders; references per fit " + std::to_string(x["references_per_fit"].get<int>()) + "; model weather maps " +
        std::to_string(x["model_weather_maps"].get<int>()) + ", renders per evaluation " +
        std::to_string(x["model_renders"].get<int>()) + ", at most " + std::to_string(x["max_iterations"].get<int>()) +
        " iterations; fitted: " + x["fitted"].get<std::string>() + "; residuals " +
        (x["noise_draws"].get<int>() > 0 ? "whitened by the shape noise of " + std::to_string(x["noise_draws"].get<int>()) +
                                               " draws at the start"
                                         : std::string("weighted by bin share")) +
        "; model noise textures " + std::to_string(x["model_noise_textures"].get<int>()) + Whitening(x) + ".\n\n" +
        "| pair (noise/weather) | extinction | g1 | powder | ambient | albedo | cost start -> end | iterations | renders | "
        "time (s) |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : x["runs"]) {
    const auto seeds = [&](const char* key) {
      return std::to_string(r[key][0].get<uint64_t>()) + "/" + std::to_string(r[key][1].get<uint64_t>());
    };
    md += "| " + (r["control_known_shapes"].get<bool>() ? std::string("control (same seeds)")
                                                        : seeds("reference_seeds") + " vs " + seeds("model_seeds"));
    for (const auto& [name, f] : StartFactors())
      md += " | " + (r["parameters"].contains(name) ? SignedPct(r["parameters"][name]["rel_error"].get<double>())
                                                    : std::string("-"));
    md += " | " + FormatG(r["initial_cost"].get<double>()) + " -> " + FormatG(r["final_cost"].get<double>()) + " | " +
          std::to_string(r["iterations"].get<int>()) + " | " + std::to_string(r["renders"].get<long long>()) + " | " +
          FormatFixed(r["time_s"].get<double>(), 1) + " |\n";
  }
  md += "\n| spread over the unknown-shape pairs | median abs | max abs |\n|---|---|---|\n";
  for (const auto& [name, f] : StartFactors())
    if (x["spread"].contains(name))
      md += "| " + name + " | " + FormatFixed(100.0 * x["spread"][name]["median_abs_rel_error"].get<double>(), 1) +
          "% | " + FormatFixed(100.0 * x["spread"][name]["max_abs_rel_error"].get<double>(), 1) + "% |\n";
  return md;
}

std::string SeedPairMarkdown(const std::string& suite_name, const std::vector<CaseResult>& cases) {
  std::string md =
      "# Cloud lighting from statistics, unknown shapes: seed pairs\n\n"
      "`skycal bench --suite " + suite_name + "` (bench/src/fit_cloud_stats_suite.cc; numbers in `results.json`). "
      "Reference: default_cloudy's lighting, sun 25 deg up at azimuth 30, noise seed / weather seed as listed; the fit "
      "renders with the other seeds (other shapes, the same weather statistics) from the truth x (extinction 1.3 unless "
      "the case says otherwise, g1 0.7, powder 0.7, ambient 1.3, albedo 0.7) for the fitted parameters, the others held at "
      "the truth. Relative error (fitted - truth) / truth. Times on a shared machine (noisy).\n\n" +
      CaseTable(cases, "median abs rel error", {{"pairs", [](const CaseResult& c) { return ExtraNumber(c, "pairs"); }}});
  for (const CaseResult& c : cases) {
    if (!c.extra.contains("runs")) continue;
    md += SeedPairSection(c);
  }
  return md;
}

// The pairs' fits: error (median |rel error| of the fitted parameters), outcome and extra into c.
void SummariseSeedPairs(CaseResult& c, const nlohmann::json& runs, const CloudStatsPlan& plan, const CloudStatsConfig& cfg,
                        const cloudfit::CloudStatsOptions& options, const clouds::CloudRenderer& renderer) {
  std::vector<double> fitted_errors;
  nlohmann::json spread;
  for (const auto& [name, f] : StartFactors()) {
    std::vector<double> e;
    for (const auto& r : runs)
      if (!r["control_known_shapes"].get<bool>()) e.push_back(std::abs(r["parameters"][name]["rel_error"].get<double>()));
    const bool is_fitted = std::find(options.fitted.begin(), options.fitted.end(), name) != options.fitted.end();
    if (is_fitted) fitted_errors.insert(fitted_errors.end(), e.begin(), e.end());
    spread[name] = {{"median_abs_rel_error", Median(e)},
                    {"max_abs_rel_error", e.empty() ? 0.0 : *std::max_element(e.begin(), e.end())},
                    {"fitted", is_fitted}};
  }
  c.error = Median(fitted_errors);
  bool finite = std::isfinite(c.error);
  for (const auto& r : runs) finite = finite && std::isfinite(r["final_cost"].get<double>());
  if (!finite) {
    c.outcome = Outcome::kNonFinite;
    c.message = "non-finite fitted parameter or cost";
  }
  c.extra = {{"runs", runs},
             {"spread", spread},
             {"pairs", plan.pairs},
             {"render_width", options.render_width},
             {"references_per_fit", cfg.references},
             {"model_weather_maps", cfg.model_maps},
             {"model_renders", options.model_renders},
             {"max_iterations", options.max_iterations},
             {"fitted", Join(options.fitted)},
             {"noise_draws", options.noise_draws},
             {"noise_covariance", options.noise_covariance},
             {"draw_noise_textures", cfg.draw_noises},
             {"extinction_start", cfg.extinction_start},
             {"model_noise_textures", cfg.model_noises},
             {"renderer", renderer.Describe()},
             {"results_file", cfg.results_file},
             {"program_args", cfg.program_args}};
}

std::vector<CaseResult> RunSeedPairs(const std::string& suite_name, CloudStatsPlan (*plan_of)(bool), const SuiteOptions& o) {
  const CloudStatsPlan plan = plan_of(o.quick);
  const std::string cache = CloudStatsCacheDir();
  const std::unique_ptr<clouds::CloudRenderer> renderer = CreateCloudStatsRenderer();
  return RunGrid(suite_name, plan.grid, o, [&](CaseResult& c) {
    const CloudStatsConfig& cfg = FindCloudStatsConfig(plan, Get(c.settings, "config"));
    const cloudfit::CloudStatsOptions options = OptionsFor(plan, cfg);
    nlohmann::json runs = nlohmann::json::array();
    c.time = Measure(
        [&] {
          runs = nlohmann::json::array();
          for (int k = cfg.references > 1 ? 1 : 0; k <= plan.pairs; ++k)
            runs.push_back(RunPair(k, cfg, options, *renderer, cache, o));
        },
        0, 1);  // one run: each pair is a fit of seconds to minutes
    SummariseSeedPairs(c, runs, plan, cfg, options, *renderer);
  });
}

// The seed-pair suite over `plan_of(quick)`'s configurations (fit-cloud-stats and fit-cloud-stats-gls).
Suite SeedPairSuite(const std::string& suite_name, const std::string& summary, CloudStatsPlan (*plan_of)(bool)) {
  Suite s;
  s.name = suite_name;
  s.summary = summary;
  s.error_metric = "median |fitted / truth - 1| of the fitted lighting parameters over the unknown-shape seed pairs";
  s.error_axis = "median |rel error| of the fitted lighting";
  s.markdown = [suite_name](const std::vector<CaseResult>& cases) { return SeedPairMarkdown(suite_name, cases); };
  s.run = [suite_name, plan_of](const SuiteOptions& o) { return RunSeedPairs(suite_name, plan_of, o); };
  return s;
}

}  // namespace

Suite FitCloudStatsSuite() {
  return SeedPairSuite("fit-cloud-stats",
                       "the unknown-shapes cloud lighting fit over 5 seed pairs + a control, per configuration (--quick: "
                       "2 configurations, 1 pair at 64x32)",
                       FitCloudStatsPlan);
}

Suite FitCloudStatsGlsSuite() {
  return SeedPairSuite("fit-cloud-stats-gls",
                       "the full GLS against the diagonal whitening, same draws, 5 seed pairs + a control at 64x32 "
                       "(--quick: the 3 cheaper test-* settings, 5 pairs each)",
                       FitCloudStatsGlsPlan);
}

}  // namespace skycal::bench
