// Fitting the game's sky model to reference skies with Ceres (`skycal fit`).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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

}  // namespace skycal::fit
