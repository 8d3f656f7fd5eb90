// Random-start stress study of `skycal fit`: many fits from starting presets far from any
// sky (each LUT table scaled 0.1x-10x, g uniform in [0, 0.95]) on references whose
// exposure is off by up to 10^+-3, over clear skies the preset was not built from (CIE
// general skies, other atmospheres' bakes; 256x128). A fit succeeds when its rel RMSE is
// within 1.2 x the model's LUT ceiling + 0.1% (fit/include/skycal/fit/ceiling.h) and every
// output is finite. Failures are listed with their start.
//
// Usage: bench_fit_stress [--starts N] [--out DIR]   (N random starts per sky, default 20;
// 10 skies). Writes DIR/fit_stress.json and fit_stress.md (default bench/results).
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/json_file.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"

using namespace skycal;

namespace {

constexpr int kWidth = 256;

struct Sky {
  std::string name;
  fit::Reference ref;
  double ceiling = 0.0;
};

bool Finite(const render::Preset& p) {
  for (const auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
    for (float v : *t)
      if (!std::isfinite(v)) return false;
  return std::isfinite(p.haziness_g) && std::isfinite(p.overcast_zenith_cd_m2);
}

}  // namespace

int main(int argc, char** argv) {
  int starts = 20;
  std::filesystem::path out_dir = std::string(SKYCAL_SOURCE_DIR) + "/bench/results";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--starts") starts = std::stoi(argv[i + 1]);
    else if (a == "--out") out_dir = argv[i + 1];
    else {
      std::cerr << "bench_fit_stress: unknown option " << a << " (expected --starts N, --out DIR)\n";
      return 2;
    }
  }
  const auto dir = std::filesystem::temp_directory_path() / ("skycal-bench-stress-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const render::Preset preset = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  fit::FitOptions o;
  o.verbose = false;
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);

  // Ten clear skies: six CIE general skies, four bakes of other atmospheres.
  std::vector<Sky> skies;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const std::pair<int, double> cie[] = {{1, 30}, {3, 15}, {7, 45}, {12, 30}, {13, 10}, {15, 60}};
  for (const auto& [t, el] : cie) {
    const std::string path = (dir / ("cie" + std::to_string(t) + ".exr")).string();
    refsky::WriteCieReference(path, types[t - 1], latlong::DirectionFromElevationAzimuthDeg(el, 30.0), kWidth);
    skies.push_back({"CIE " + std::to_string(t) + " sun " + std::to_string(int(el)), fit::LoadReference(path, o), 0.0});
  }
  const auto variants = refsky::StandardAtmosphereVariants();
  const std::pair<int, double> bakes[] = {{0, 10}, {1, 45}, {2, 2}, {1, -3}};
  for (const auto& [v, el] : bakes) {
    const std::string path = (dir / (variants[v].name + std::to_string(int(el)) + ".exr")).string();
    refsky::WriteModelReference(path, refsky::BakeVariant(variants[v]), latlong::DirectionFromElevationAzimuthDeg(el, -70.0), kWidth);
    skies.push_back({variants[v].name + " sun " + std::to_string(int(el)), fit::LoadReference(path, o), 0.0});
  }
  for (Sky& s : skies) s.ceiling = fit::ModelCeiling(s.ref, preset, o).lut_rel_rmse;

  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  nlohmann::json fits = nlohmann::json::array(), failures = nlohmann::json::array();
  int ok = 0, finite = 0, total = 0;
  std::vector<double> ratios, times;
  for (const Sky& sky : skies) {
    for (int k = 0; k < starts; ++k) {
      render::Preset start = preset;
      double scales[3];
      for (int t = 0; t < 3; ++t) scales[t] = std::pow(10.0, -1.0 + 2.0 * u(rng));
      int t = 0;
      for (auto* table : {&start.luts.rayleigh, &start.luts.mie, &start.luts.isotropic}) {
        for (float& v : *table) v = static_cast<float>(v * scales[t]);
        ++t;
      }
      start.haziness_g = 0.95 * u(rng);
      const double exposure = std::pow(10.0, -3.0 + 6.0 * u(rng));
      fit::Reference ref = sky.ref;
      for (float& v : ref.radiance.pixels) v = static_cast<float>(v * exposure);
      ref.clip_level *= exposure;
      nlohmann::json start_json = {{"sky", sky.name},
                                   {"table_scales", {scales[0], scales[1], scales[2]}},
                                   {"g", start.haziness_g},
                                   {"reference_exposure", exposure}};
      ++total;
      try {
        const auto t0 = std::chrono::steady_clock::now();
        const fit::FitResult r = fit::FitSky({ref}, start, o, *vulkan);
        times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        const double err = r.references[0].errors.rel_rmse;
        const bool is_finite = Finite(r.preset) && std::isfinite(err) && std::isfinite(r.references[0].exposure);
        const bool success = is_finite && err <= 1.2 * sky.ceiling + 1e-3;
        finite += is_finite;
        ok += success;
        ratios.push_back(err / std::max(sky.ceiling, 1e-9));
        start_json["rel_rmse"] = err;
        start_json["ceiling"] = sky.ceiling;
        start_json["success"] = success;
        if (!success) failures.push_back(start_json);
      } catch (const std::exception& e) {
        start_json["error"] = e.what();
        failures.push_back(start_json);
      }
      fits.push_back(start_json);
    }
    std::cerr << "[stress] " << sky.name << ": " << ok << "/" << total << " successes so far\n";
  }
  std::sort(ratios.begin(), ratios.end());
  std::sort(times.begin(), times.end());
  const double rate = static_cast<double>(ok) / std::max(total, 1);
  const nlohmann::json result = {{"benchmark", "random-start stress study (bench/bench_fit_stress.cc)"},
                                 {"machine", bench::MachineInfo()},
                                 {"fits", total},
                                 {"successes", ok},
                                 {"success_rate", rate},
                                 {"finite_outputs", finite},
                                 {"fit_over_ceiling_median", ratios.empty() ? 0.0 : ratios[ratios.size() / 2]},
                                 {"fit_over_ceiling_max", ratios.empty() ? 0.0 : ratios.back()},
                                 {"fit_time_median_ms", times.empty() ? 0.0 : times[times.size() / 2]},
                                 {"failures", failures},
                                 {"all", fits}};
  std::filesystem::create_directories(out_dir);
  WriteJsonFileAtomically((out_dir / "fit_stress.json").string(), result);
  std::ostringstream md;
  md << std::setprecision(4) << "# Random-start stress study\n\n`bench_fit_stress --starts " << starts << "`, "
     << result["machine"]["date_utc"].get<std::string>() << ": " << total << " fits over " << skies.size()
     << " clear skies (256x128; six CIE general skies, four bakes of other atmospheres), each from a start with every "
        "LUT table scaled by 10^U(-1, 1), g ~ U(0, 0.95), and the reference's exposure off by 10^U(-3, 3).\n\n"
     << "- success (rel RMSE <= 1.2 x LUT ceiling + 0.1%, finite): **" << ok << "/" << total << " = " << 100 * rate
     << "%**\n- finite outputs: " << finite << "/" << total << "\n- fit / ceiling: median "
     << result["fit_over_ceiling_median"].get<double>() << ", worst " << result["fit_over_ceiling_max"].get<double>()
     << "\n- fit time median: " << result["fit_time_median_ms"].get<double>() << " ms\n\n";
  md << (failures.empty() ? std::string("No failures.\n") : std::string("Failures (start and outcome):\n\n"));
  for (const auto& f : failures) md << "- " << f.dump() << "\n";
  WriteFileAtomically((out_dir / "fit_stress.md").string(), md.str());
  std::cout << md.str();
  std::filesystem::remove_all(dir);
  return 0;
}
