// The unknown-shapes cloud lighting fit (fit/include/skycal/fit/cloud_stats.h) over seed
// pairs: each reference is rendered with one noise seed and weather-map seed, the fit uses
// another pair (the shapes differ entirely, the weather statistics are the same) and starts
// from the true lighting perturbed by up to 30%. Writes the recovery error per parameter
// and pair, the spread, the Jacobian's singular values, renders and time per fit to
// bench/results/cloud_stats_seed_pairs.md (+ .json); the control pair fits with the
// reference's own seeds (known shapes).
//
// Usage: bench_cloud_stats [PAIRS (default 6)] [OUT_STEM] [RENDER_WIDTH (default 256)] [REFERENCES_PER_FIT (default 1)]
//                          [MODEL_WEATHER_MAPS (default 1)] [MODEL_RENDERS (default: the options' 2)] [MAX_ITERATIONS]
//   further references of a fit use noise/weather seeds (1 + k + 10 j, 11 + k + 10 j); with
//   MODEL_WEATHER_MAPS E > 1 the model pools renders of E weather maps (seeds 211 + k + 1000 e),
//   MODEL_RENDERS in all (render m: map m % E, wind (m / E) * 1800 s)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_util.h"
#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/core/error.h"

namespace {

using namespace skycal;

// Start: the truth times these factors (clamped into the spec's bounds).
const std::vector<std::pair<std::string, double>> kStart = {
    {"extinction", 1.3}, {"phase_g1", 0.7}, {"powder_strength", 0.7}, {"ambient_strength", 1.3}};

double* Field(clouds::CloudParams& p, const std::string& name) {
  for (const auto& s : clouds::CloudParameterSpecs())
    if (name == s.name) return s.field(p);
  throw Error("no cloud field " + name);
}

std::string FittedList(const fit::CloudStatsOptions& o) {
  std::string s;
  for (const auto& n : o.fitted) s += (s.empty() ? "" : ",") + n;
  return s;
}

}  // namespace

int RunCloudStatsNoise(int argc, char** argv);  // cloud_stats_noise.cc
int RunCloudStatsScan(int argc, char** argv);   // cloud_stats_noise.cc

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "noise") return RunCloudStatsNoise(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "scan") return RunCloudStatsScan(argc, argv);
  const int pairs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 6;
  const std::string stem = argc > 2 ? argv[2] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/cloud_stats_seed_pairs";
  const std::string cache = bench::CloudStatsCacheDir();
  const std::unique_ptr<clouds::CloudRenderer> renderer = bench::CreateCloudStatsRenderer();
  fit::CloudStatsOptions options;
  if (argc > 3) {
    options.render_width = std::max(16, std::atoi(argv[3]));
    options.render_height = options.render_width / 2;
  }
  // References per fit (the same lighting over several skies: the reference side's shape
  // noise averages out); more than 1 skips the control.
  const int refs_per_fit = argc > 4 ? std::max(1, std::atoi(argv[4])) : 1;
  // The model's ensemble of shape draws (weather-map seeds) and its renders per evaluation.
  const int model_maps = argc > 5 ? std::max(1, std::atoi(argv[5])) : 1;
  if (argc > 6) options.model_renders = std::max(1, std::atoi(argv[6]));
  if (argc > 7) options.max_iterations = std::max(0, std::atoi(argv[7]));
  // FITTED: a comma list of the parameters fitted (default: the options' four); the others
  // of the four are held at the truth (the start is not perturbed for them).
  if (argc > 8) {
    options.fitted.clear();
    std::stringstream list(argv[8]);
    for (std::string name; std::getline(list, name, ',');) options.fitted.push_back(name);
  }
  // NOISE_DRAWS: whiten the residuals by the shape noise of that many draws (independent
  // weather maps, seeds 5000 + d) measured at the start (options.noise_draws; 0: off).
  if (argc > 9) options.noise_draws = std::max(0, std::atoi(argv[9]));
  std::vector<clouds::WeatherMap> noise_maps;
  // MODEL_NOISES: the model's renders cycle through that many noise textures (seeds
  // 101 + k + 1000 i; 1: the model's one texture).
  const int model_noises = argc > 10 ? std::max(1, std::atoi(argv[10])) : 1;
  nlohmann::json runs = nlohmann::json::array();
  std::vector<std::vector<double>> errors(kStart.size());  // per parameter, over the unknown-shape pairs
  std::ostringstream rows;
  for (int k = refs_per_fit > 1 ? 1 : 0; k <= pairs; ++k) {
    const bool control = k == 0;  // the known-shapes control: model seeds = reference seeds
    const bench::CloudStatsSeeds ref_seeds{static_cast<uint64_t>(1 + k), static_cast<uint64_t>(11 + k)};
    const bench::CloudStatsSeeds model_seeds =
        control ? ref_seeds : bench::CloudStatsSeeds{static_cast<uint64_t>(101 + k), static_cast<uint64_t>(211 + k)};
    std::fprintf(stderr, "pair %d/%d: reference seeds %llu/%llu, model seeds %llu/%llu\n", k, pairs,
                 static_cast<unsigned long long>(ref_seeds.noise), static_cast<unsigned long long>(ref_seeds.weather),
                 static_cast<unsigned long long>(model_seeds.noise), static_cast<unsigned long long>(model_seeds.weather));
    auto scene = bench::MakeCloudStatsScene(SKYCAL_SOURCE_DIR, ref_seeds, model_seeds, 25.0, 30.0, options, *renderer, cache);
    clouds::CloudParams start = scene.truth;
    for (const auto& [name, f] : kStart) {
      if (std::find(options.fitted.begin(), options.fitted.end(), name) == options.fitted.end()) continue;
      const auto& specs = clouds::CloudParameterSpecs();
      const auto it = std::find_if(specs.begin(), specs.end(), [&](const auto& s) { return name == s.name; });
      *Field(start, name) = std::clamp(*Field(scene.truth, name) * f, it->min, it->max);
    }
    fit::CloudStatsScene model{&scene.preset, start, &scene.noise, &scene.weather};
    std::vector<clouds::WeatherMap> ensemble;
    if (!control && model_maps > 1) {
      ensemble.push_back(scene.weather);
      for (int e = 1; e < model_maps; ++e)
        ensemble.push_back(bench::CloudStatsWeather(model_seeds.weather + 1000 * e, scene.truth.weather_extent_m));
      for (const auto& w : ensemble) model.weather_ensemble.push_back(&w);
    }
    if (options.noise_draws > 0) {
      if (noise_maps.empty())
        for (int d = 0; d < options.noise_draws; ++d)
          noise_maps.push_back(bench::CloudStatsWeather(5000 + d, scene.truth.weather_extent_m));
      for (const auto& w : noise_maps) model.shape_draw_maps.push_back(&w);
    }
    std::vector<clouds::CloudNoise> textures;
    if (!control && model_noises > 1) {
      for (int i = 1; i < model_noises; ++i) {
        std::fprintf(stderr, "  noise texture seed %llu\n", static_cast<unsigned long long>(model_seeds.noise + 1000 * i));
        textures.push_back(clouds::LoadOrGenerateCloudNoise(model_seeds.noise + 1000 * i, cache));
      }
      model.noise_textures.push_back(&scene.noise);
      for (const auto& t : textures) model.noise_textures.push_back(&t);
    }
    // The control renders the model once, at the reference's own wind time: the same shapes.
    fit::CloudStatsOptions run_options = options;
    if (control) run_options.model_renders = 1;
    std::vector<fit::CloudStatsReference> refs = {scene.reference};
    for (int j = 1; j < refs_per_fit; ++j) {
      const bench::CloudStatsSeeds more{static_cast<uint64_t>(1 + k + 10 * j), static_cast<uint64_t>(11 + k + 10 * j)};
      refs.push_back(
          bench::MakeCloudStatsScene(SKYCAL_SOURCE_DIR, more, model_seeds, 25.0, 30.0, options, *renderer, cache).reference);
    }
    const fit::CloudStatsResult res = fit::FitCloudStats(refs, model, *renderer, run_options);
    nlohmann::json run = {{"control_known_shapes", control},
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
                          {"model_noise_textures", control ? 1 : model_noises},
                          {"median_noise_sd", res.median_noise_sd},
                          {"termination", res.termination}};
    rows << "| " << (control ? "control (same seeds)" : std::to_string(ref_seeds.noise) + "/" + std::to_string(ref_seeds.weather) +
                                                           " vs " + std::to_string(model_seeds.noise) + "/" +
                                                           std::to_string(model_seeds.weather));
    for (size_t j = 0; j < kStart.size(); ++j) {
      clouds::CloudParams fitted = res.params, truth = scene.truth;
      const double t = *Field(truth, kStart[j].first), v = *Field(fitted, kStart[j].first);
      const double err = (v - t) / t;
      run["parameters"][kStart[j].first] = {{"truth", t}, {"start", *Field(start, kStart[j].first)}, {"fitted", v}, {"rel_error", err}};
      if (!control) errors[j].push_back(std::abs(err));
      char buf[48];
      std::snprintf(buf, sizeof buf, " | %+.1f%%", 100.0 * err);
      rows << buf;
    }
    char tail[96];
    std::snprintf(tail, sizeof tail, " | %.3g -> %.3g | %d | %lld | %.1f |\n", res.initial_cost, res.final_cost, res.iterations,
                  res.renders, res.time_s);
    rows << tail;
    std::fprintf(stderr, "  %s\n", res.termination.c_str());
    for (size_t j = 0; j < kStart.size(); ++j)
      std::fprintf(stderr, "  %s %+.1f%%", kStart[j].first.c_str(), 100.0 * run["parameters"][kStart[j].first]["rel_error"].get<double>());
    std::fprintf(stderr, "\n  cost %.3g -> %.3g, %d iterations, %lld renders, %.1f s\n", res.initial_cost, res.final_cost,
                 res.iterations, res.renders, res.time_s);
    runs.push_back(run);
  }
  std::ostringstream md;
  md << "# Cloud lighting from statistics, unknown shapes: seed pairs\n\n"
     << "References per fit: " << refs_per_fit << "; the model's weather maps (shape draws) per evaluation: "
     << model_maps << ", renders per evaluation " << options.model_renders << ", at most " << options.max_iterations
     << " iterations.\n\n"
     << "`build/bench/bench_cloud_stats " << pairs << " STEM " << options.render_width << " " << refs_per_fit << " "
     << model_maps << " " << options.model_renders << " " << options.max_iterations << " " << FittedList(options) << " "
     << options.noise_draws << " " << model_noises << "` (model noise textures: " << model_noises << "; residuals " << (options.noise_draws > 0 ? "whitened by the shape noise of " + std::to_string(options.noise_draws) + " draws at the start" : std::string("weighted by bin share"))
     << "; fitted: " << FittedList(options) << "; fit/include/skycal/fit/cloud_stats.h, default options: "
     << options.render_width << "x" << options.render_height << " renders, bins sun angle 0-20-45-90-180 deg x elevation "
     << "2-15-35-90 deg x opacity thin/thick, quantiles 0.25-0.5-0.75 of log radiance per channel and the thick "
     << "share per bin; the model's statistics pool " << options.model_renders << " renders "
     << options.model_time_step_s << " s of wind apart (the control: 1 render, the reference's own shapes); central "
     << "differences through " << renderer->Describe() << "). Reference: default_cloudy's lighting, sun 25 deg up at "
     << "azimuth 30, noise seed / weather seed as listed; the fit renders with the other seeds (other shapes, the same "
     << "weather statistics) from the truth x (extinction 1.3, g1 0.7, powder 0.7, ambient 1.3); the other lighting fields held at the truth. "
     << "Relative error of each fitted parameter (fitted - truth) / truth. Times on the shared 2-core machine (noisy).\n\n"
     << "| pair (noise/weather) | extinction | g1 | powder | ambient | cost start -> end | iterations | renders | time (s) |\n"
     << "|---|---|---|---|---|---|---|---|---|\n"
     << rows.str() << "\n| spread over the unknown-shape pairs | median abs | max abs |\n|---|---|---|\n";
  nlohmann::json spread;
  for (size_t j = 0; j < kStart.size(); ++j) {
    std::vector<double> e = errors[j];
    std::sort(e.begin(), e.end());
    const double med = bench::Median(e), mx = e.empty() ? 0.0 : e.back();
    spread[kStart[j].first] = {{"median_abs_rel_error", med}, {"max_abs_rel_error", mx}};
    char buf[128];
    std::snprintf(buf, sizeof buf, "| %s | %.1f%% | %.1f%% |\n", kStart[j].first.c_str(), 100.0 * med, 100.0 * mx);
    md << buf;
  }
  std::ofstream(stem + ".md") << md.str();
  std::ofstream(stem + ".json") << nlohmann::json{{"machine", bench::MachineJson()},
                                                  {"references_per_fit", refs_per_fit},
                                                  {"model_weather_maps", model_maps},
                                                  {"model_renders", options.model_renders},
                                                  {"render_width", options.render_width},
                                                  {"runs", runs},
                                                  {"spread", spread}}
                                       .dump(2)
                                << "\n";
  std::fprintf(stderr, "wrote %s.md/.json\n", stem.c_str());
  return 0;
}
