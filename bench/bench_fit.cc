// Benchmark of `skycal fit` where users start: the bundled default preset, default
// options, references the preset was not built from (CIE general skies, other
// atmospheres' bakes), 512x256. Per reference: fit time (median of repeats after a
// warm-up), the linear start's stages, the error against the model's ceiling
// (fit/include/skycal/fit/ceiling.h). In the same run, on a subset: the old path
// (coarse-to-fine Ceres, no linear start), the numeric-Jacobian baseline, the whole
// process (`skycal fit` as a user runs it), and a 24-reference day. Each skip decision's
// measured saving: the Ceres polish (--polish forces it) and the coarse levels (the old
// path).
//
// Writes bench/results/fit.json and fit.md (or into argv[1], a directory). With
// --decisions [DIR]: only bench/results/fit_decisions.md + .json, each skip decision
// switched off through FitOptions on a few skies (fit_decision_table.h). With --day: only
// the 24-reference day, printed as JSON (no files written).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "bench_util.h"
#include "fit_decision_table.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/fit_json.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"

using namespace skycal;

namespace {

constexpr int kWidth = 512;
constexpr int kRepeats = 3;

render::Preset DefaultStart() {
  return render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
}

struct Case {
  std::string name, path;
};

std::vector<Case> WriteReferences(const std::filesystem::path& dir) {
  std::vector<Case> cases;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  for (int t : {1, 3, 7, 12, 15}) {
    for (double el : {10.0, 30.0, 60.0}) {
      Case c{"CIE " + std::to_string(t) + " sun " + std::to_string(int(el)), (dir / ("cie" + std::to_string(t) + "_" + std::to_string(int(el)) + ".exr")).string()};
      refsky::WriteCieReference(c.path, types[t - 1], latlong::DirectionFromElevationAzimuthDeg(el, 20.0), kWidth);
      cases.push_back(c);
    }
  }
  for (const auto& v : refsky::StandardAtmosphereVariants()) {
    const render::Preset truth = refsky::BakeVariant(v);
    for (double el : {2.0, 30.0, 70.0}) {
      Case c{v.name + " sun " + std::to_string(int(el)), (dir / (v.name + std::to_string(int(el)) + ".exr")).string()};
      refsky::WriteModelReference(c.path, truth, latlong::DirectionFromElevationAzimuthDeg(el, -50.0), kWidth);
      cases.push_back(c);
    }
  }
  return cases;
}

using bench::Median;

struct Run {
  fit::FitResult result;
  bench::Timing timing;
};

Run TimeFit(const std::vector<fit::Reference>& refs, const fit::FitOptions& o, render::SkyRenderer& renderer, int runs,
            int warmup = 1) {
  Run r;
  r.timing = bench::Measure([&] { r.result = fit::FitSky(refs, DefaultStart(), o, renderer); }, warmup, runs);
  return r;
}

// Wall time of the binary, as a user runs it (load, fit, render, write outputs).
double ProcessSeconds(const std::string& reference, const std::filesystem::path& out) {
  std::filesystem::remove_all(out);
  const std::string cmd = std::string(SKYCAL_BINARY) + " fit --quiet --reference '" + reference + "' --out '" +
                          out.string() + "' > /dev/null 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = std::system(cmd.c_str());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rc != 0) throw Error("bench_fit: `" + cmd + "` failed");
  return s;
}

double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// The day: 24 references of the hazy atmosphere, sun -4 .. 80 deg, 256x128, one fit each
// way; with `old_path`, the coarse-to-fine Ceres path too (~40 s). The linear stage's
// parts (linear_start.day) are reported beside the total.
nlohmann::json DayJson(const std::filesystem::path& dir, const fit::FitOptions& defaults, render::SkyRenderer& vulkan,
                       bool old_path) {
  const render::Preset truth = refsky::BakeVariant(refsky::StandardAtmosphereVariants()[1]);
  std::vector<fit::Reference> refs;
  for (int i = 0; i < 24; ++i) {
    const std::string path = (dir / ("day_" + std::to_string(i) + ".exr")).string();
    refsky::WriteModelReference(path, truth, latlong::DirectionFromElevationAzimuthDeg(-4.0 + 84.0 * i / 23.0, -100.0 + 9.0 * i), 256);
    refs.push_back(fit::LoadReference(path, defaults));
  }
  // CPU seconds of the process (both threads) beside the wall time: the machine is shared,
  // and under load the wall time measures the neighbours as much as the fit.
  const double cpu0 = ProcessCpuSeconds();
  const Run day = TimeFit(refs, defaults, vulkan, 1, 0);
  const double cpu_s = ProcessCpuSeconds() - cpu0;
  double worst = 0.0;
  for (const auto& r : day.result.references) worst = std::max(worst, r.errors.rel_rmse);
  const fit::LinearStartDayReport ls = day.result.linear_start.day.value_or(fit::LinearStartDayReport{});
  nlohmann::json out = {{"timing", day.timing.ToJson()},
                        {"cpu_s", cpu_s},
                        {"rel_rmse_max", worst},
                        {"haziness_g", day.result.preset.haziness_g},
                        {"truth_haziness_g", refsky::StandardAtmosphereVariants()[1].haziness_g},
                        {"levels", fit::FitSummaryJson(day.result)["levels"]},
                        {"linear_start_time_s", day.result.linear_start.time_s()},
                        {"linear_start_parts_s", {{"per_reference_starts", ls.per_reference_time_s},
                                                  {"joint_steps", ls.joint_time_s},
                                                  {"render_check", ls.render_check.time_s}}}};
  // The per-reference starts' stages, summed over the references (they run two at a time).
  double search = 0.0, robust = 0.0, solves = 0.0;
  for (const auto& [name, single] : ls.references) {
    search += single.search_time_s;
    robust += single.robust_time_s + single.final_time_s;
    solves += single.solves;
  }
  out["per_reference_stages_summed_s"] = {{"g_search", search}, {"robust_steps", robust}, {"solves", solves}};
  out["joint_robust_cost_per_step"] = ls.joint_robust_cost_per_step;
  std::cerr << "[bench fit] day: " << day.timing.median_ms << " ms (linear stage " << 1e3 * ls.time_s
            << " ms: per-reference starts " << 1e3 * ls.per_reference_time_s << ", joint steps "
            << 1e3 * ls.joint_time_s << ", render check " << 1e3 * ls.render_check.time_s << "; " << cpu_s
            << " s CPU), worst rel "
            << 100 * worst << "%, g " << day.result.preset.haziness_g << "\n";
  if (old_path) {
    fit::FitOptions old = defaults;
    old.linear_start = false;
    const Run old_day = TimeFit(refs, old, vulkan, 1, 0);
    double old_worst = 0.0;
    for (const auto& r : old_day.result.references) old_worst = std::max(old_worst, r.errors.rel_rmse);
    out["old_path"] = {{"timing", old_day.timing.ToJson()}, {"rel_rmse_max", old_worst},
                       {"haziness_g", old_day.result.preset.haziness_g}};
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // --decisions [DIR]: only the per-decision table (bench/fit_decision_table.h).
  const bool decisions_only = argc > 1 && std::string(argv[1]) == "--decisions";
  const bool day_only = argc > 1 && std::string(argv[1]) == "--day";
  const int dir_arg = decisions_only || day_only ? 2 : 1;
  const std::filesystem::path out_dir =
      argc > dir_arg ? argv[dir_arg] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results";
  const auto dir = std::filesystem::temp_directory_path() / ("skycal-bench-fit-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  if (day_only) {
    // --day: only the day (no old path), printed; for before/after comparisons.
    fit::FitOptions defaults;
    defaults.verbose = false;
    auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
    std::cout << DayJson(dir, defaults, *vulkan, false).dump(2) << "\n";
    std::filesystem::remove_all(dir);
    return 0;
  }
  if (decisions_only) {
    bench::WriteDecisionTable(DefaultStart(), dir, out_dir);
    std::filesystem::remove_all(dir);
    return 0;
  }
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  fit::FitOptions defaults;
  defaults.verbose = false;
  nlohmann::json result = {{"benchmark", "fit from the bundled default preset, default options (ffxv-iso, Cauchy, linear "
                                         "start, vulkan render check), 512x256 references the preset was not built from"},
                           {"machine", bench::MachineJson()}};

  // 1. Every reference: the default fit, its stages and its ceiling.
  const std::vector<Case> cases = WriteReferences(dir);
  nlohmann::json per_ref = nlohmann::json::array();
  std::vector<double> times, ratios, search, robust, final_s, check;
  for (const Case& c : cases) {
    const fit::Reference ref = fit::LoadReference(c.path, defaults);
    const Run run = TimeFit({ref}, defaults, *vulkan, kRepeats);
    const fit::CeilingResult ceiling = fit::ModelCeiling(ref, DefaultStart(), defaults);
    const fit::LinearStartSingleReport ls = run.result.linear_start.single.value_or(fit::LinearStartSingleReport{});
    const double err = run.result.references[0].errors.rel_rmse;
    times.push_back(run.timing.median_ms);
    ratios.push_back(err / std::max(ceiling.lut_rel_rmse, 1e-9));
    search.push_back(1e3 * ls.search_time_s);
    robust.push_back(1e3 * ls.robust_time_s);
    final_s.push_back(1e3 * ls.final_time_s);
    check.push_back(1e3 * (ls.render_check ? ls.render_check->time_s : 0.0));
    per_ref.push_back({{"reference", c.name},
                       {"timing", run.timing.ToJson()},
                       {"rel_rmse", err},
                       {"ceiling_lut", ceiling.lut_rel_rmse},
                       {"ceiling_per_row", ceiling.per_row_rel_rmse},
                       {"within_1.2x_ceiling_plus_0.1pct", err <= 1.2 * ceiling.lut_rel_rmse + 1e-3},
                       {"haziness_g", run.result.preset.haziness_g},
                       {"linear_start", fit::ToJson(run.result.linear_start)}});
    std::cerr << "[bench fit] " << c.name << ": " << run.timing.median_ms << " ms, rel " << 100 * err << "%, ceiling "
              << 100 * ceiling.lut_rel_rmse << "%\n";
  }
  result["single_512x256"] = per_ref;
  result["summary"] = {{"fit_time_median_ms", Median(times)},
                       {"fit_time_max_ms", *std::max_element(times.begin(), times.end())},
                       {"stage_median_ms", {{"g_search", Median(search)}, {"robust_steps", Median(robust)},
                                            {"final_level_steps", Median(final_s)}, {"render_check", Median(check)}}},
                       {"fit_over_ceiling_median", Median(ratios)},
                       {"references", cases.size()}};

  // 2. A subset: old path, numeric baseline, forced polish, whole process.
  nlohmann::json compare = nlohmann::json::array();
  for (size_t k : {size_t{1}, size_t{10}, size_t{16}}) {
    const Case& c = cases[k];
    const fit::Reference ref = fit::LoadReference(c.path, defaults);
    fit::FitOptions old_path = defaults, polish = defaults, numeric = defaults;
    old_path.linear_start = false;
    polish.polish = true;
    numeric.linear_start = false;
    numeric.numeric_derivatives = true;
    numeric.backend = render::Backend::kCpu;
    numeric.pyramid_widths = {kWidth};
    numeric.max_iterations_per_level = 200;
    fit::FitOptions default_cpu = defaults;
    default_cpu.backend = render::Backend::kCpu;
    const Run d = TimeFit({ref}, defaults, *vulkan, kRepeats);
    const Run dc = TimeFit({ref}, default_cpu, *cpu, kRepeats);
    const Run p = TimeFit({ref}, polish, *vulkan, 1);
    const Run old = TimeFit({ref}, old_path, *vulkan, 1);
    const Run num = TimeFit({ref}, numeric, *cpu, 1);
    std::vector<double> process;
    for (int i = 0; i < kRepeats; ++i) process.push_back(ProcessSeconds(c.path, dir / "process_out"));
    auto describe = [](const Run& r) {
      return nlohmann::json{{"median_ms", r.timing.median_ms},
                            {"rel_rmse", r.result.references[0].errors.rel_rmse},
                            {"ceres_iterations", r.result.iterations}};
    };
    compare.push_back({{"reference", c.name},
                       {"default_vulkan", describe(d)},
                       {"default_cpu", describe(dc)},
                       {"with_ceres_polish", describe(p)},
                       {"old_coarse_to_fine_ceres", describe(old)},
                       {"numeric_jacobian_baseline", describe(num)},
                       {"speedup_vs_numeric_baseline", num.timing.median_ms / dc.timing.median_ms},
                       {"speedup_vs_old_path", old.timing.median_ms / d.timing.median_ms},
                       {"polish_skip_saves_ms", p.timing.median_ms - d.timing.median_ms},
                       {"whole_process_median_s", Median(process)}});
    std::cerr << "[bench fit] " << c.name << ": default " << d.timing.median_ms << " ms, polish " << p.timing.median_ms
              << " ms, old " << old.timing.median_ms << " ms, numeric " << num.timing.median_ms << " ms, process "
              << Median(process) << " s\n";
  }
  result["comparisons"] = compare;

  // 3. A day: 24 references of the hazy atmosphere, sun -4 .. 80 deg, 256x128, one fit.
  result["day_24_references_256x128"] = DayJson(dir, defaults, *vulkan, true);
  result["targets"] = {{"single_512x256_fit_median_ms_max", 300.0}, {"single_512x256_process_median_s_max", 0.6},
                       {"speedup_vs_numeric_baseline_min", 15.0}, {"day_24_median_ms_max", 3000.0}};
  std::filesystem::create_directories(out_dir);
  WriteJsonFileAtomically((out_dir / "fit.json").string(), result);

  // The readable summary.
  std::ostringstream md;
  md << std::fixed << std::setprecision(3);
  md << "# Fit benchmark (bench/bench_fit.cc)\n\nFrom the bundled default preset, default options, 512x256 references "
        "the preset was not built from. Machine: " << bench::MachineJson()["hardware_threads"] << " hardware threads, "
     << result["machine"]["date_utc"].get<std::string>() << ".\n\n"
     << "| reference | fit ms (median of " << kRepeats << ") | rel RMSE % | LUT ceiling % | g |\n|---|---|---|---|---|\n";
  for (const auto& r : per_ref) {
    md << "| " << r["reference"].get<std::string>() << " | " << r["timing"]["median_ms"].get<double>() << " | "
       << 100 * r["rel_rmse"].get<double>() << " | " << 100 * r["ceiling_lut"].get<double>() << " | "
       << r["haziness_g"].get<double>() << " |\n";
  }
  md << "\nMedian fit time " << Median(times) << " ms; stages (median ms): g search " << Median(search)
     << ", robust steps " << Median(robust) << ", final level " << Median(final_s) << ", render check " << Median(check)
     << ".\n\n| reference | default (vulkan) ms | default (cpu) ms | + Ceres polish ms | old coarse-to-fine ms | "
        "numeric baseline ms | vs numeric | process s |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : compare) {
    md << "| " << c["reference"].get<std::string>() << " | " << c["default_vulkan"]["median_ms"].get<double>() << " ("
       << 100 * c["default_vulkan"]["rel_rmse"].get<double>() << "%) | " << c["default_cpu"]["median_ms"].get<double>()
       << " | " << c["with_ceres_polish"]["median_ms"].get<double>() << " ("
       << 100 * c["with_ceres_polish"]["rel_rmse"].get<double>() << "%) | "
       << c["old_coarse_to_fine_ceres"]["median_ms"].get<double>() << " ("
       << 100 * c["old_coarse_to_fine_ceres"]["rel_rmse"].get<double>() << "%) | "
       << c["numeric_jacobian_baseline"]["median_ms"].get<double>() << " ("
       << 100 * c["numeric_jacobian_baseline"]["rel_rmse"].get<double>() << "%) | "
       << c["speedup_vs_numeric_baseline"].get<double>() << "x | " << c["whole_process_median_s"].get<double>() << " |\n";
  }
  const auto& day = result["day_24_references_256x128"];
  md << "\nDay (24 references of the hazy atmosphere, 256x128, one run): " << day["timing"]["median_ms"].get<double>()
     << " ms (linear stage " << 1e3 * day["linear_start_time_s"].get<double>() << " ms: the per-reference starts "
     << 1e3 * day["linear_start_parts_s"]["per_reference_starts"].get<double>() << " ms, the day's joint Gauss-Newton steps "
     << 1e3 * day["linear_start_parts_s"]["joint_steps"].get<double>() << " ms, the render check "
     << 1e3 * day["linear_start_parts_s"]["render_check"].get<double>() << " ms; the rest the final renders), "
     << "worst rel RMSE " << 100 * day["rel_rmse_max"].get<double>() << "%, g " << day["haziness_g"].get<double>()
     << " (truth " << day["truth_haziness_g"].get<double>() << "); the old coarse-to-fine path: "
     << day["old_path"]["timing"]["median_ms"].get<double>() << " ms, worst " << 100 * day["old_path"]["rel_rmse_max"].get<double>()
     << "%.\n";
  WriteFileAtomically((out_dir / "fit.md").string(), md.str());
  std::cout << md.str();
  std::filesystem::remove_all(dir);
  return 0;
}
