// Fitting the game's sky model to reference skies with Ceres (`skycal fit`).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/capture/probe.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_options.h"
#include "skycal/fit/fit_report.h"
#include "skycal/fit/reference.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::fit {

struct ImageErrors {
  double rel_rmse = 0.0;  // solid-angle weighted RMS of (fit - ref) / ref, fitted pixels, 3 channels
  double log_rmse = 0.0;  // same weighting, RMS of ln(fit) - ln(ref)
  long long pixels = 0;
};
// Errors of `fit` (already multiplied by the exposure) against the reference's kSky pixels.
ImageErrors CompareToReference(const Reference& ref, const ImageRGB& fit);
// The preset rendered at the reference's pixels (exposure not applied): its size, and for
// horizon-biased rows a uniform render resampled onto them (core/row_mapping.h).
ImageRGB RenderAtReference(const Reference& ref, const render::Preset& preset, render::SkyRenderer& renderer);

// ---- The gray diffuse probe (fit/src/probe_cost.h, fit/src/sun_from_probe.cc) -----------
// Probe samples of one frame, as `skycal probe-extract` writes them ("skycal-probe-samples").
struct ProbeSamples {
  std::string path;
  double albedo = 0.18;
  std::vector<capture::ProbeSample> samples;
  double max_luminance = 0.0;
  bool max_luminance_clipped = false;
};
// Throws skycal::Error naming the file when it is unreadable or not a valid samples file.
ProbeSamples LoadProbeSamples(const std::string& path);

// The sun of one probed reference, as the joint fit found it.
struct ProbeSun {
  bool observable = false;                    // E_sun was a parameter (see `note` when not)
  std::string note;                           // why not observable / why occluded
  bool visible = false;
  std::array<double, 3> illuminance_ref{};    // recovered E_sun, the reference's units (0 when occluded)
  std::array<double, 3> illuminance_model{};  // illuminance_ref / exposure (model units; lux when absolute)
  std::array<double, 3> fitted_model{};       // the least-squares E_sun / exposure, whatever the decision
  double lux = 0.0;                           // Rec.709 luminance of illuminance_model
  // fraction: the sun term's share of the brightest sun-facing samples (capture::SunShare);
  // residual: RMS(R - P) / RMS(R) over samples and channels; log_rmse: RMS of log(P / R).
  double fraction = 0.0, residual = 0.0, log_rmse = 0.0;
  int samples = 0, sun_facing_samples = 0, ground_facing_samples = 0;
};
struct ReferenceFit {
  double exposure = 1.0;   // fitted image = exposure * model (1 with --absolute)
  ImageErrors errors;
  ImageRGB rendered;       // model * exposure at the reference's size and sun, sun disc on
  std::vector<int> observed_rows;  // LUT rows this reference constrains
  std::optional<ProbeSun> sun;     // with probe samples
};

// Typed throughout (fit_report.h); skycal/fit/fit_result_file.h writes it into fit.json.
struct FitResult {
  render::Preset preset;
  std::vector<ReferenceFit> references;
  double time_s = 0.0;
  int iterations = 0;
  std::string termination;
  std::vector<LevelReport> levels;       // per Ceres pyramid level that ran
  std::vector<SkipNote> skipped;         // parameter blocks / passes not needed, with reasons
  std::vector<FitDecision> decisions;    // what was not evaluated, and what that saved
  std::vector<UnobservedRow> unobserved_rows;
  std::string backend_description;
  std::vector<std::string> warnings;  // e.g. a failed render check
  LinearStartReportOut linear_start;  // fit/src/linear_start.h; empty when it did not run
  // With probe samples: weight, quadrature, residual counts, the ground albedo (fitted or
  // held, and why), the time spent evaluating the probe residuals.
  std::optional<ProbeReport> probe;
};

// Fits `init` (grid, sun, overcast weight ...) to the references. `renderer` is the
// selected backend (kept alive by the caller so its pipelines are reused).
// probes: empty, or one entry per reference (nullptr: no probe for that reference). A
// probed reference adds its probe residuals, its sun illuminance block and (when samples
// face the ground) the shared ground albedo to the same Ceres problem (fit/src/probe_cost.h).
FitResult FitSky(const std::vector<Reference>& references, const render::Preset& init, const FitOptions& options,
                 render::SkyRenderer& renderer, const std::vector<const ProbeSamples*>& probes = {});

// sun_tint_rgb such that sun_illuminance_lux * tint * SunTransmittance(sun zenith) equals
// `illuminance_model`, clamped to the parameter's bounds (*clamped set when it was).
std::array<double, 3> SunTintFor(const render::Preset& preset, const std::array<double, 3>& sun_dir,
                                 const std::array<double, 3>& illuminance_model, bool* clamped);

}  // namespace skycal::fit
