#include "fit_decision_table.h"

#include <iomanip>
#include <iostream>
#include <sstream>

#include "bench_util.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"

namespace skycal::bench {
namespace {

constexpr int kWidth = 512;
constexpr int kRuns = 3;

struct Sky {
  std::string name;
  fit::Reference ref;
};

// Three skies the preset was not built from: a CIE sky the model cannot reach (ceiling
// ~2%), a clear and a hazy bake with a low sun.
std::vector<Sky> Skies(const std::filesystem::path& dir, const fit::FitOptions& o) {
  std::vector<Sky> skies;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const std::string cie = (dir / "decisions_cie12_30.exr").string();
  refsky::WriteCieReference(cie, types[11], latlong::DirectionFromElevationAzimuthDeg(30.0, 20.0), kWidth);
  skies.push_back({"CIE 12 sun 30", fit::LoadReference(cie, o)});
  const auto variants = refsky::StandardAtmosphereVariants();
  for (const auto& [k, el] : {std::pair<size_t, double>{0, 30.0}, {1, 2.0}}) {
    const std::string path = (dir / ("decisions_" + variants[k].name + ".exr")).string();
    refsky::WriteModelReference(path, refsky::BakeVariant(variants[k]),
                                latlong::DirectionFromElevationAzimuthDeg(el, -50.0), kWidth);
    skies.push_back({variants[k].name + " sun " + std::to_string(static_cast<int>(el)), fit::LoadReference(path, o)});
  }
  return skies;
}

struct Measured {
  double ms = 0.0, rel_rmse = 0.0;
  fit::FitResult result;
};

Measured Fit(const fit::Reference& ref, const render::Preset& start, const fit::FitOptions& o,
             render::SkyRenderer& renderer) {
  Measured m;
  m.ms = Measure([&] { m.result = fit::FitSky({ref}, start, o, renderer); }, 1, kRuns).median_ms;
  m.rel_rmse = m.result.references[0].errors.rel_rmse;
  return m;
}

// One decision: the fit with it (on) and without it (off), same start.
struct Switch {
  std::string row, what;
  fit::FitOptions on, off;
  bool overcast_start = false;  // start from the default preset with an overcast weight
};

}  // namespace

void WriteDecisionTable(const render::Preset& start, const std::filesystem::path& scratch,
                        const std::filesystem::path& out_dir) {
  auto renderer = render::CreateRenderer(render::Backend::kVulkan);
  fit::FitOptions defaults;
  defaults.verbose = false;
  const std::vector<Sky> skies = Skies(scratch, defaults);
  // The overcast decision needs a term to hold: the default preset with weight 0.2.
  render::Preset overcast_start = start;
  overcast_start.overcast_weight = 0.2;

  std::vector<Switch> switches;
  {
    Switch s{"Ceres polish", "Ceres polish skipped after the linear start (off: --polish)", defaults, defaults};
    s.off.polish = true;
    switches.push_back(s);
  }
  {
    // Measured with the polish running in both, so the polish's own cost is not counted
    // twice: off runs the coarse pyramid levels (64, 128, 256 wide) before the finest.
    Switch s{"coarse levels", "coarse pyramid levels skipped after the linear start (both with --polish)", defaults,
             defaults};
    s.on.polish = s.off.polish = true;
    s.off.skip_coarse_levels = false;
    switches.push_back(s);
  }
  {
    Switch s{"overcast held (ffxv-iso)", "L_z held in ffxv-iso (overcast_weight 0.2 start)", defaults, defaults};
    s.off.hold_inseparable_overcast = false;
    s.overcast_start = true;
    switches.push_back(s);
  }

  nlohmann::json rows = nlohmann::json::array();
  std::ostringstream md;
  md << std::setprecision(4);
  md << "# Skip decisions of the fit (bench/bench_fit.cc --decisions)\n\nEach decision switched off through "
        "FitOptions on " << skies.size() << " skies of " << kWidth << "x" << kWidth / 2
     << " from the bundled default preset (Vulkan backend, median of " << kRuns << " runs after a warm-up). "
        "saved ms = fit time with the decision off minus on; rel RMSE change = with the skip minus without "
        "(percentage points; negative: the skip lowered the error). Machine: "
     << MachineJson()["hardware_threads"] << " hardware threads, " << MachineJson()["date_utc"].get<std::string>()
     << ".\n\n| decision | sky | on ms | off ms | saved ms | rel RMSE on % | off % | change (pp) |\n"
        "|---|---|---|---|---|---|---|---|\n";
  nlohmann::json medians;
  std::vector<double> samples, pixel_saved;
  for (const Switch& s : switches) {
    std::vector<double> saved, change;
    for (const Sky& sky : skies) {
      const render::Preset& st = s.overcast_start ? overcast_start : start;
      const Measured on = Fit(sky.ref, st, s.on, *renderer);
      const Measured off = Fit(sky.ref, st, s.off, *renderer);
      saved.push_back(off.ms - on.ms);
      change.push_back(on.rel_rmse - off.rel_rmse);
      if (&s == &switches.front()) {
        samples.push_back(static_cast<double>(on.result.linear_start.samples()));
        for (const fit::FitDecision& d : on.result.decisions) {
          if (d.what.find("below the horizon") != std::string::npos) pixel_saved.push_back(d.saved_ms);
        }
      }
      rows.push_back({{"decision", s.row}, {"sky", sky.name}, {"on_ms", on.ms}, {"off_ms", off.ms},
                      {"rel_rmse_on", on.rel_rmse}, {"rel_rmse_off", off.rel_rmse}});
      md << "| " << s.what << " | " << sky.name << " | " << on.ms << " | " << off.ms << " | " << off.ms - on.ms
         << " | " << 100 * on.rel_rmse << " | " << 100 * off.rel_rmse << " | " << 100 * (on.rel_rmse - off.rel_rmse)
         << " |\n";
      std::cerr << "[bench fit decisions] " << s.row << ", " << sky.name << ": on " << on.ms << " ms, off " << off.ms
                << " ms\n";
    }
    medians[s.row] = {{"saved_ms", Median(saved)}, {"rel_rmse_change", Median(change)}};
  }
  medians["samples"] = Median(samples);
  md << "\n| decision | median saved ms | median rel RMSE change (pp) | basis |\n|---|---|---|---|\n";
  for (const Switch& s : switches) {
    md << "| " << s.row << " | " << medians[s.row]["saved_ms"].get<double>() << " | "
       << 100 * medians[s.row]["rel_rmse_change"].get<double>() << " | measured (switched off) |\n";
  }
  md << "| pixels below the horizon not evaluated | " << Median(pixel_saved)
     << " | 0 (not in the error measure) | estimated in fit.json: the skipped samples x the run's measured time per "
        "evaluated sample (not switchable: the ground has no sky value to match) |\n"
     << "| unobserved LUT rows / columns held | 0 | 0 | none: no pixel reads them (not switchable) |\n"
     << "| probe blocks only where samples exist | 0 | 0 | none: nothing to evaluate without samples |\n"
     << "\nMedian fitted samples (pixels x channels) of the final level: " << Median(samples)
     << " (the scale fit.json's estimates use, fit/src/fit_decisions.cc).\n";
  std::filesystem::create_directories(out_dir);
  WriteJsonFileAtomically((out_dir / "fit_decisions.json").string(),
                          {{"machine", MachineJson()}, {"rows", rows}, {"medians", medians}});
  WriteFileAtomically((out_dir / "fit_decisions.md").string(), md.str());
  std::cout << md.str();
}

}  // namespace skycal::bench
