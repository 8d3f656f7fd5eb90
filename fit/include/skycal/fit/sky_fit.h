// Fitting the game's sky model to reference skies with Ceres (`skycal fit`).
#pragma once
#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/probe.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_options.h"
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

struct ReferenceFit {
  double exposure = 1.0;   // fitted image = exposure * model (1 with --absolute)
  ImageErrors errors;
  ImageRGB rendered;       // model * exposure at the reference's size and sun, sun disc on
  std::vector<int> observed_rows;  // LUT rows this reference constrains
};

struct FitResult {
  render::Preset preset;
  std::vector<ReferenceFit> references;
  double time_s = 0.0;
  int iterations = 0;
  std::string termination;
  nlohmann::json levels = nlohmann::json::array();   // per pyramid level: size, iterations, cost, time
  nlohmann::json skipped = nlohmann::json::array();  // parameter blocks / passes not needed, with reasons
  nlohmann::json unobserved_rows = nlohmann::json::array();
  std::string backend_description;
};

// Fits `init` (grid, sun, overcast weight ...) to the references. `renderer` is the
// selected backend (kept alive by the caller so its pipelines are reused).
FitResult FitSky(const std::vector<Reference>& references, const render::Preset& init, const FitOptions& options,
                 render::SkyRenderer& renderer);

// ---- The sun from the gray diffuse probe (fit/src/sun_from_probe.cc) ------------------
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

struct ProbeSun {
  bool visible = false;
  std::array<double, 3> illuminance_ref{};    // recovered E_sun, the reference's units (0 when occluded)
  std::array<double, 3> illuminance_model{};  // illuminance_ref / exposure (model units; lux when absolute)
  std::array<double, 3> fitted_model{};       // the least-squares E_sun / exposure, whatever the decision
  double lux = 0.0;                           // Rec.709 luminance of illuminance_model
  double fraction = 0.0, residual = 0.0;      // capture::SunRecovery sun_fraction, residual_rms_rel
  int samples = 0, sun_facing_samples = 0;
};
// Renders `fitted` at the reference's sun without the disc (sky_width x sky_width/2),
// E_sky at the sample normals by quadrature times rf.exposure, then capture::RecoverSun.
ProbeSun SunFromProbe(const Reference& ref, const ReferenceFit& rf, const render::Preset& fitted,
                      const ProbeSamples& probe, render::SkyRenderer& renderer, int sky_width = 512);

// sun_tint_rgb such that sun_illuminance_lux * tint * SunTransmittance(sun zenith) equals
// `illuminance_model`, clamped to the parameter's bounds (*clamped set when it was).
std::array<double, 3> SunTintFor(const render::Preset& preset, const std::array<double, 3>& sun_dir,
                                 const std::array<double, 3>& illuminance_model, bool* clamped);

}  // namespace skycal::fit
