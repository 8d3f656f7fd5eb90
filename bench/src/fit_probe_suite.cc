// Suite `fit-probe`: the joint sky + gray-probe fit (fit --probe; fit/src/probe_cost.h) on a
// reference whose sun is clipped, so only the ball can tell the sun's illuminance (what
// bench_probe_fit measured, now a suite). Truth: the synthetic ffxv-iso preset
// (tests/synthetic_sky.h) with the sun tinted (0.85, 1, 1.12) away from the preset's and a
// ground of albedo 0.25; start: the smooth +-20% LUT perturbation, g + 0.06, ground 0.1, the
// preset's tint. Reference: 2% noise, clipped above its 99.5th percentile (one exposure);
// ball: albedo 0.18, 1% noise, its sun side clipped (tests/synthetic_probe.h). --absolute
// (the exposure is the gauge: one reference). Grid: FitProbeGrid (fit_suite_grids.h).
// Time: one fit, median of repeats; error: the worst channel of |E_sun / truth - 1|, the
// sun's illuminance at the ground -- the probe's recovered sun, or without a probe the
// fitted preset's (sun x tint x transmittance: the start's tint, which the clipped sky
// cannot correct). `extra`: the sky's error against the clean truth, g, the ground albedo,
// the probe's log RMSE.
#include <algorithm>
#include <cmath>
#include <map>

#include "skycal/bench/fit_suite_grids.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/irradiance.h"
#include "suite_util.h"
#include "suites_internal.h"
#include "skycal/testing/synthetic_probe.h"
#include "skycal/testing/synthetic_sky.h"

namespace skycal::bench {
namespace {

constexpr double kElevation = 35.0, kAzimuth = 50.0;  // deg
constexpr double kBallAlbedo = 0.18;

// A noisy reference clipped above the 99.5th percentile of its green channel.
std::string WriteClippedReference(const std::string& dir, const render::Preset& truth, int width) {
  const std::string path = dir + "/probe_ref" + std::to_string(width) + ".exr";
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

// Solid-angle RMS of fit / truth - 1 above the horizon, outside 3 deg of the sun.
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

double WorstChannelError(const std::array<double, 3>& e, const render::Rgb& truth) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(e[c] / truth[c] - 1.0));
  return worst;
}

}  // namespace

Grid FitProbeGrid(bool quick) {
  Grid grid;
  const std::vector<std::string> sizes =
      quick ? std::vector<std::string>{"128x64", "256x128"} : std::vector<std::string>{"256x128", "512x256"};
  const std::vector<std::string> weights =
      quick ? std::vector<std::string>{"0.1", "10"} : std::vector<std::string>{"0.01", "0.1", "1", "10"};
  // Defaults: a reference with its probe (fit finds <stem>.probe.json), FitOptions (vulkan,
  // probe_weight 0.1, the ground albedo fitted).
  grid.axes = {{"probe", {"on", "off"}, "on"},
               {"backend", {"vulkan", "cpu"}, "vulkan"},
               {"size", sizes, sizes[0]},
               {"probe_weight", weights, "0.1"},
               {"scenario", {"consistent", "ball-albedo-5pct-high", "ground-held-low"}, "consistent"}};
  const std::string default_size = sizes[0];
  grid.skip = [default_size](const Settings& st) -> std::string {
    const bool swept = Get(st, "probe_weight") != "0.1" || Get(st, "scenario") != "consistent";
    if (Get(st, "probe") == "off" && swept) return "the sky-only fit has no probe weight and no ball";
    if (swept && (Get(st, "backend") != "vulkan" || Get(st, "size") != default_size))
      return "probe weight and scenarios: swept at the default backend and size";
    return "";
  };
  return grid;
}

namespace {

std::string FitProbeMarkdown(const std::vector<CaseResult>& cases) {
  return "# skycal bench --suite fit-probe\n\nThe joint sky + gray-probe fit (what bench_probe_fit measured): synthetic "
         "ffxv-iso truth, sun 35 deg tinted (0.85, 1, 1.12), ground albedo 0.25; reference 2% noise, clipped above "
         "its 99.5th percentile; ball 0.18, 1% noise. Sun error: worst channel of the recovered illuminance at the "
         "ground (the probe's; without one the fitted preset's); sky error: solid-angle RMS of fit / truth - 1 "
         "against the clean sky, above the horizon, outside 3 deg of the sun. The scenarios lie to the fit: "
         "`ball-albedo-5pct-high` tells it 0.189; `ground-held-low` holds the ground albedo at 0.1.\n\n" +
         CaseTable(cases, "sun error (fraction)",
                   {{"sky error %", [](const CaseResult& c) { return ExtraNumber(c, "sky_rel_rmse_vs_clean_truth", 100.0); }},
                    {"g (truth 0.76)", [](const CaseResult& c) { return ExtraNumber(c, "haziness_g"); }},
                    {"ground albedo (truth 0.25)", [](const CaseResult& c) { return ExtraNumber(c, "ground_albedo"); }},
                    {"probe log RMSE", [](const CaseResult& c) { return ExtraNumber(c, "probe_log_rmse"); }},
                    {"Ceres iterations", [](const CaseResult& c) { return ExtraNumber(c, "ceres_iterations"); }}}) +
         "\nThe sun error is a fraction (0.011 = 1.1%).\n";
}

// The truth (tinted sun, ground 0.25), the fit's start, the sun and its illuminance at the
// ground, the ball's samples; per size the reference's path and the clean truth's render.
struct ProbeStudy {
  render::Preset truth, start;
  std::array<double, 3> sun{};
  render::Rgb e_sun{};
  fit::ProbeSamples probe;
  std::map<std::string, std::string> ref_paths;
  std::map<std::string, ImageRGB> clean;
};

ProbeStudy MakeProbeStudy(const SuiteOptions& o, const Grid& grid) {
  ProbeStudy st;
  render::Preset& truth = st.truth;
  truth = synthetic::TruthPreset(render::ModelVariant::kFfxvIso);
  const std::array<double, 3> tint_scale = {0.85, 1.0, 1.12};
  for (int c = 0; c < 3; ++c) truth.sun_tint_rgb[c] *= tint_scale[c];
  truth.ground_albedo = 0.25;
  st.start = synthetic::PerturbedStart(truth, 3);
  st.start.ground_albedo = 0.1;
  for (int c = 0; c < 3; ++c) st.start.sun_tint_rgb[c] /= tint_scale[c];
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(kElevation, kAzimuth);
  st.sun = sun;
  st.e_sun = render::SunIlluminanceAtGround(truth, sun);
  st.probe.path = "synthetic";
  st.probe.albedo = kBallAlbedo;
  st.probe.samples = synthetic::ProbeSamplesFor(truth, sun, st.e_sun, kBallAlbedo, 0.01, 7, 0.25);
  o.Log("[fit-probe] truth: ffxv-iso, sun 35 deg tinted (0.85, 1, 1.12), ground 0.25; ball 0.18, " +
        std::to_string(st.probe.samples.size()) + " samples");

  // The references (the fit's input) and the clean truth (the sky error's) per size.
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  for (const std::string& size : grid.axes[2].values) {
    const int w = std::stoi(size.substr(0, size.find('x')));
    st.ref_paths[size] = WriteClippedReference(o.scratch.string(), truth, w);
    render::RenderRequest req;
    req.sun_dir = sun;
    req.width = w;
    req.height = w / 2;
    st.clean[size] = cpu->Render(truth, req);
  }
  return st;
}

// One case: the fit (with the ball or without), timed; the sun's recovered illuminance
// against the truth, the sky against the clean truth.
void RunProbeCase(CaseResult& c, const SuiteOptions& o, const ProbeStudy& st,
                  std::map<std::string, std::unique_ptr<render::SkyRenderer>>& renderers, int repeats) {
  const std::string& scenario = Get(c.settings, "scenario");
  fit::FitOptions f;
  f.verbose = false;
  f.absolute = true;
  f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
  f.probe_weight = std::stod(Get(c.settings, "probe_weight"));
  f.fit_ground_albedo = scenario != "ground-held-low";  // held at the start's 0.1 (truth 0.25)
  fit::ProbeSamples told = st.probe;
  if (scenario == "ball-albedo-5pct-high") told.albedo = kBallAlbedo * 1.05;
  const bool with_probe = Get(c.settings, "probe") == "on";
  const std::string& size = Get(c.settings, "size");
  const std::vector<fit::Reference> refs = {fit::LoadReference(st.ref_paths.at(size), f)};
  std::vector<const fit::ProbeSamples*> probes;
  if (with_probe) probes.push_back(&told);
  fit::FitResult r;
  c.time = Measure([&] { r = fit::FitSky(refs, st.start, f, *renderers.at(Get(c.settings, "backend")), probes); },
                   o.warmup, repeats);
  const fit::ReferenceFit& rf = r.references.at(0);
  std::array<double, 3> recovered{};
  if (with_probe) {
    recovered = rf.sun.value().illuminance_model;
  } else {
    const render::Rgb e = render::SunIlluminanceAtGround(r.preset, st.sun);
    for (int k = 0; k < 3; ++k) recovered[k] = e[k];
  }
  c.error = WorstChannelError(recovered, st.e_sun);
  const double sky = SkyError(rf.rendered, st.clean.at(size), st.sun);
  c.converged = std::isfinite(c.error) && std::isfinite(sky) && std::isfinite(r.preset.haziness_g);
  if (!*c.converged) {
    c.outcome = Outcome::kNonFinite;
    c.message = "non-finite sun illuminance, sky error or g";
  }
  c.extra = {{"sky_rel_rmse_vs_clean_truth", sky},
             {"haziness_g", r.preset.haziness_g},
             {"truth_haziness_g", st.truth.haziness_g},
             {"ground_albedo", r.preset.ground_albedo},
             {"truth_ground_albedo", st.truth.ground_albedo},
             {"sun_illuminance_model", recovered},
             {"ceres_iterations", r.iterations}};
  if (with_probe) {
    c.extra["probe_log_rmse"] = rf.sun->log_rmse;
    c.extra["probe_samples"] = told.samples.size();
  }
}

}  // namespace

Suite FitProbeSuite() {
  Suite s;
  s.name = "fit-probe";
  s.summary = "joint sky + gray-probe fit, sun clipped in the sky: probe on/off x backend x size x probe weight x scenario";
  s.error_metric = "worst channel of |E_sun / truth - 1|, the sun's illuminance at the ground (probe's, else the preset's)";
  s.error_axis = "sun illuminance error (worst channel)";
  s.markdown = FitProbeMarkdown;
  s.run = [](const SuiteOptions& o) {
    const Grid grid = FitProbeGrid(o.quick);
    const ProbeStudy st = MakeProbeStudy(o, grid);
    auto renderers = SkyRenderersByBackend();
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    return RunGrid("fit-probe", grid, o, [&](CaseResult& c) { RunProbeCase(c, o, st, renderers, repeats); });
  };
  return s;
}

}  // namespace skycal::bench
