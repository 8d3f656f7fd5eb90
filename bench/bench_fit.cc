// Benchmark of `skycal fit` (after loading): median wall time of a single-reference
// 512x256 fit per backend and model variant, the straightforward baseline (numeric
// Jacobians, full resolution, one pyramid level) measured in the same run at its error,
// and a 24-reference day fit. Writes bench/results/fit.json (or argv[1]).
#include <filesystem>
#include <iostream>

#include "bench_util.h"
#include "skycal/core/json_file.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "../tests/synthetic_sky.h"

using namespace skycal;

namespace {

struct Run {
  bench::Timing timing;
  fit::FitResult last;
};

Run TimeFit(const std::vector<fit::Reference>& refs, const render::Preset& start, const fit::FitOptions& o,
            render::SkyRenderer& renderer, int runs) {
  Run r;
  r.timing = bench::Measure([&] { r.last = fit::FitSky(refs, start, o, renderer); }, 1, runs);
  return r;
}

nlohmann::json Describe(const Run& r) {
  double worst = 0.0;
  for (const auto& ref : r.last.references) worst = std::max(worst, ref.errors.rel_rmse);
  return {{"timing", r.timing.ToJson()}, {"iterations", r.last.iterations}, {"rel_rmse_max", worst},
          {"haziness_g", r.last.preset.haziness_g}};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/fit.json";
  const auto dir = std::filesystem::temp_directory_path() / "skycal-bench-fit";
  std::filesystem::create_directories(dir);
  nlohmann::json result = {{"benchmark", "fit after loading; synthetic references from the bundled preset, "
                                         "start = smooth +-20% LUT perturbation and g + 0.06 (truth g = 0.76)"},
                           {"machine", bench::MachineInfo()}};
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);

  // Single reference, 512x256, sun 30 deg.
  nlohmann::json single = nlohmann::json::object();
  for (auto variant : {render::ModelVariant::kFfxv, render::ModelVariant::kFfxvIso}) {
    const render::Preset truth = synthetic::TruthPreset(variant);
    const std::string path = (dir / (std::string("single_") + render::ToString(variant) + ".exr")).string();
    synthetic::WriteSyntheticReference(path, truth, 30.0, 25.0, 512);
    const render::Preset start = synthetic::PerturbedStart(truth, 3);
    for (auto backend : {render::Backend::kVulkan, render::Backend::kCpu}) {
      fit::FitOptions o;
      o.variant = variant;
      o.backend = backend;
      o.verbose = false;
      const std::vector<fit::Reference> refs = {fit::LoadReference(path, o)};
      render::SkyRenderer& renderer = backend == render::Backend::kVulkan ? *vulkan : *cpu;
      const Run run = TimeFit(refs, start, o, renderer, 7);
      const std::string key = std::string(render::ToString(variant)) + "/" + render::ToString(backend);
      single[key] = Describe(run);
      std::cerr << "[bench fit] single " << key << ": median " << run.timing.median_ms << " ms, rel_rmse "
                << run.last.references[0].errors.rel_rmse << "\n";
    }
  }
  result["single_512x256"] = single;

  // Baseline: numeric (central-difference) Jacobians, one level at full resolution, CPU
  // model; against the default (analytic, pyramid) on the same reference, same run.
  {
    const render::Preset truth = synthetic::TruthPreset(render::ModelVariant::kFfxvIso);
    const std::string path = (dir / "single_ffxv-iso.exr").string();
    const render::Preset start = synthetic::PerturbedStart(truth, 3);
    fit::FitOptions fast;
    fast.variant = render::ModelVariant::kFfxvIso;
    fast.backend = render::Backend::kCpu;
    fast.verbose = false;
    fit::FitOptions base = fast;
    base.numeric_derivatives = true;
    base.pyramid_widths = {512};
    base.max_iterations_per_level = 200;
    const std::vector<fit::Reference> refs = {fit::LoadReference(path, fast)};
    const Run f = TimeFit(refs, start, fast, *cpu, 5);
    const Run b = TimeFit(refs, start, base, *cpu, 3);
    result["baseline_comparison"] = {
        {"reference", "ffxv-iso 512x256, cpu backend for both"},
        {"skycal", Describe(f)},
        {"baseline_numeric_full_resolution", Describe(b)},
        {"speedup", b.timing.median_ms / f.timing.median_ms}};
    std::cerr << "[bench fit] baseline " << b.timing.median_ms << " ms vs " << f.timing.median_ms << " ms: "
              << b.timing.median_ms / f.timing.median_ms << "x\n";
  }

  // A day: 24 references at 256x128, sun from -4 to 80 deg elevation, one fit.
  {
    const render::Preset truth = synthetic::TruthPreset(render::ModelVariant::kFfxvIso);
    fit::FitOptions o;
    o.variant = render::ModelVariant::kFfxvIso;
    o.backend = render::Backend::kVulkan;
    o.verbose = false;
    std::vector<fit::Reference> refs;
    for (int i = 0; i < 24; ++i) {
      const double elevation = -4.0 + 84.0 * i / 23.0;
      const std::string path = (dir / ("day_" + std::to_string(i) + ".exr")).string();
      synthetic::WriteSyntheticReference(path, truth, elevation, -100.0 + 9.0 * i, 256);
      refs.push_back(fit::LoadReference(path, o));
    }
    const Run d = TimeFit(refs, synthetic::PerturbedStart(truth, 4), o, *vulkan, 3);
    result["day_24_references_256x128_vulkan"] = Describe(d);
    std::cerr << "[bench fit] day: median " << d.timing.median_ms << " ms\n";
  }
  result["targets"] = {{"single_512x256_median_ms_max", 500.0}};
  WriteJsonFileAtomically(out, result);
  std::cout << result.dump(2) << std::endl;
  std::filesystem::remove_all(dir);
  return 0;
}
