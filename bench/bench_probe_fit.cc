// Benchmark of the joint sky + probe fit (fit/src/probe_cost.h, probe_terms.h):
//  1. the added cost of probe residuals: one 512x256 reference fitted with and without its
//     probe samples, per backend, medians of 5 runs after a warm-up, in one run;
//  2. the probe weight against the sky pixels: a sweep of --probe-weight on a 256x128
//     reference under three scenarios (a consistent probe; the ball's albedo 5% off; the
//     ground albedo held 60% low), reporting the sun's error, the sky's error against the
//     clean truth, g and the ground albedo. (One reference's exposure is the fit's gauge,
//     held: the probe's pull on exposures needs a day of references, not measured here.)
// Truth: the synthetic ffxv-iso preset (tests/synthetic_sky.h) with the sun tinted away from
// the preset's (0.85, 1, 1.12) and a ground of albedo 0.25; start: the smooth +-20% LUT
// perturbation, g + 0.06, ground 0.1. References: 2% noise, clipped like one exposure
// (above the 99.5th percentile). Ball: albedo 0.18, 1% noise, its sun side clipped.
// Writes bench/results/probe_fit.json and bench/results/probe_weight.md (or argv[1], argv[2]).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "bench_util.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "../tests/synthetic_probe.h"
#include "../tests/synthetic_sky.h"

using namespace skycal;

namespace {

const double kElevation = 35.0, kAzimuth = 50.0;

// A noisy reference clipped above the 99.5th percentile of its green channel.
std::string WriteClippedReference(const std::filesystem::path& dir, const render::Preset& truth, int width) {
  const std::string path = (dir / ("ref" + std::to_string(width) + ".exr")).string();
  synthetic::WriteSyntheticReference(path, truth, kElevation, kAzimuth, width, 0.02, 0.0, 11);
  capture::LatLongFrame frame = capture::ReadLatLongFrame(path);
  std::vector<float> green;
  for (size_t i = 1; i < frame.radiance.pixels.size(); i += 3) green.push_back(frame.radiance.pixels[i]);
  const size_t k = green.size() * 995 / 1000;
  std::nth_element(green.begin(), green.begin() + k, green.end());
  for (float& v : frame.radiance.pixels) v = std::min(v, green[k]);
  capture::WriteLatLongFrame(path, frame);
  return path;
}

// Solid-angle RMS of fit / truth - 1 above the horizon, outside 3 degrees of the sun.
double SkyError(const ImageRGB& fitted, const ImageRGB& truth, const std::array<double, 3>& sun) {
  double se = 0.0, sw = 0.0;
  const int w = truth.width, h = truth.height;
  for (int y = 0; y < h / 2; ++y)
    for (int x = 0; x < w; ++x) {
      const auto v = latlong::PixelDirection(x, y, w, h);
      if (v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2] > std::cos(3.0 * M_PI / 180.0)) continue;
      const double omega = latlong::PixelSolidAngle(x, y, w, h);
      for (int c = 0; c < 3; ++c) {
        const double d = fitted.at(x, y, c) / truth.at(x, y, c) - 1.0;
        se += omega * d * d;
        sw += omega;
      }
    }
  return std::sqrt(se / sw);
}

double SunError(const fit::ProbeSun& s, const render::Rgb& truth) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(s.illuminance_ref[c] / truth[c] - 1.0));
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/probe_fit.json";
  const std::string table = argc > 2 ? argv[2] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/probe_weight.md";
  const auto dir = std::filesystem::temp_directory_path() / "skycal-bench-probe-fit";
  std::filesystem::create_directories(dir);
  render::Preset truth = synthetic::TruthPreset(render::ModelVariant::kFfxvIso);
  const std::array<double, 3> tint_scale = {0.85, 1.0, 1.12};
  for (int c = 0; c < 3; ++c) truth.sun_tint_rgb[c] *= tint_scale[c];
  truth.ground_albedo = 0.25;
  render::Preset start = synthetic::PerturbedStart(truth, 3);
  start.ground_albedo = 0.1;
  for (int c = 0; c < 3; ++c) start.sun_tint_rgb[c] /= tint_scale[c];
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(kElevation, kAzimuth);
  const render::Rgb e_sun = render::SunIlluminanceAtGround(truth, sun);
  fit::ProbeSamples probe;
  probe.path = "synthetic";
  probe.albedo = 0.18;
  probe.samples = synthetic::ProbeSamplesFor(truth, sun, e_sun, 0.18, 0.01, 7, 0.25);

  nlohmann::json result = {
      {"benchmark", "joint sky + probe fit, synthetic ffxv-iso truth, sun 35 deg tinted (0.85, 1, 1.12), ground "
                    "albedo 0.25; start: +-20% LUT, g + 0.06, ground 0.1; references 2% noise clipped above the "
                    "99.5th percentile; ball albedo 0.18, 1% noise, " +
                        std::to_string(probe.samples.size()) + " samples"},
      {"machine", bench::MachineJson()}};
  auto cpu = render::CreateRenderer(render::Backend::kCpu);

  // 1. Added cost, 512x256.
  {
    fit::FitOptions o;
    o.absolute = true;
    o.verbose = false;
    const std::vector<fit::Reference> refs = {fit::LoadReference(WriteClippedReference(dir, truth, 512), o)};
    nlohmann::json cost = nlohmann::json::object();
    for (auto backend : {render::Backend::kCpu, render::Backend::kVulkan}) {
      o.backend = backend;
      auto renderer = render::CreateRenderer(backend);
      fit::FitResult without, with;
      const bench::Timing t0 = bench::Measure([&] { without = fit::FitSky(refs, start, o, *renderer); }, 1, 5);
      const bench::Timing t1 = bench::Measure([&] { with = fit::FitSky(refs, start, o, *renderer, {&probe}); }, 1, 5);
      const std::string name = render::ToString(backend);
      cost[name] = {{"device", renderer->Describe()},
                    {"sky_only", t0.ToJson()},
                    {"sky_only_iterations", without.iterations},
                    {"joint", t1.ToJson()},
                    {"joint_iterations", with.iterations},
                    {"probe_evaluation_time_s_last_run", with.probe ? with.probe->evaluation_time_s : 0.0},
                    {"added_ms", t1.median_ms - t0.median_ms},
                    {"ratio", t1.median_ms / t0.median_ms},
                    {"sun_error_max_channel", SunError(*with.references[0].sun, e_sun)},
                    {"sky_rel_rmse_vs_reference", with.references[0].errors.rel_rmse}};
      std::cerr << "[bench probe-fit] " << name << ": sky only " << t0.median_ms << " ms (" << without.iterations
                << " it), joint " << t1.median_ms << " ms (" << with.iterations << " it)\n";
    }
    result["added_cost_512x256"] = cost;
  }

  // 2. Weight sweep, 256x128, CPU backend.
  struct Scenario {
    const char* name;
    double albedo_told;
    bool absolute, fit_ground;
  };
  const Scenario scenarios[] = {{"consistent", 0.18, true, true},
                                {"ball albedo 5% high", 0.189, true, true},
                                {"ground albedo held at 0.1 (truth 0.25)", 0.18, true, false}};
  const double weights[] = {0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0};
  const std::string ref256 = WriteClippedReference(dir, truth, 256);
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = 256;
  req.height = 128;
  const ImageRGB clean = cpu->Render(truth, req);
  nlohmann::json sweep = nlohmann::json::array();
  std::ostringstream md;
  md << "# Probe weight against the sky pixels (bench/bench_probe_fit.cc)\n\n"
     << "Synthetic ffxv-iso sky, sun 35 deg, 256x128 reference (2% noise, clipped), ball of 0.18 with 1% noise, "
     << "ground 0.25. Sun error: worst channel of the recovered illuminance; sky error: solid-angle RMS of "
     << "fit/truth - 1 against the clean sky (above the horizon, outside 3 deg of the sun). The sky-only fit "
     << "of the same reference is the first row of each scenario (weight 0: no probe).\n\n";
  for (const Scenario& sc : scenarios) {
    fit::FitOptions o;
    o.absolute = sc.absolute;
    o.fit_ground_albedo = sc.fit_ground;
    o.backend = render::Backend::kCpu;
    o.verbose = false;
    const std::vector<fit::Reference> refs = {fit::LoadReference(ref256, o)};
    fit::ProbeSamples told = probe;
    told.albedo = sc.albedo_told;
    md << "## " << sc.name << "\n\n| probe weight | sun error | sky error | g (truth 0.76) | ground albedo | probe log RMSE | time (s) |\n"
       << "|---|---|---|---|---|---|---|\n";
    const fit::FitResult sky_only = fit::FitSky(refs, start, o, *cpu);
    ImageRGB img = sky_only.references[0].rendered;
    md << "| 0 (sky only) | - | " << SkyError(img, clean, sun) << " | " << sky_only.preset.haziness_g << " | - | - | "
       << sky_only.time_s << " |\n";
    for (double w : weights) {
      o.probe_weight = w;
      const fit::FitResult r = fit::FitSky(refs, start, o, *cpu, {&told});
      const fit::ProbeSun& s = *r.references[0].sun;
      const double sky = SkyError(r.references[0].rendered, clean, sun);
      const double sun_err = SunError(s, e_sun);
      sweep.push_back({{"scenario", sc.name},
                       {"probe_weight", w},
                       {"sun_error", sun_err},
                       {"sky_error", sky},
                       {"g", r.preset.haziness_g},
                       {"ground_albedo", r.preset.ground_albedo},
                       {"probe_log_rmse", s.log_rmse},
                       {"exposure", r.references[0].exposure},
                       {"time_s", r.time_s},
                       {"iterations", r.iterations}});
      md << "| " << w << " | " << sun_err << " | " << sky << " | " << r.preset.haziness_g << " | " << r.preset.ground_albedo
         << " | " << s.log_rmse << " | " << r.time_s << " |\n";
      std::cerr << "[bench probe-fit] " << sc.name << " weight " << w << ": sun " << sun_err << " sky " << sky << " g "
                << r.preset.haziness_g << "\n";
    }
    md << "\n";
  }
  result["weight_sweep_256x128"] = sweep;
  WriteJsonFileAtomically(out, result);
  WriteFileAtomically(table, md.str());
  std::cerr << "[bench probe-fit] wrote " << out << " and " << table << "\n";
  return 0;
}
