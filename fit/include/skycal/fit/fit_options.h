// Options of a sky fit (`skycal fit`), validated once with IsValid (Ceres style).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::fit {

enum class RobustLoss { kNone, kCauchy, kHuber };

struct FitOptions {
  render::ModelVariant variant = render::ModelVariant::kFfxvIso;
  render::Backend backend = render::Backend::kVulkan;  // evaluates the objective
  // Sun direction for every reference (else each reference's sunDirection attribute, else
  // detection in the image).
  std::optional<std::array<double, 3>> sun_dir;
  double sun_cone_deg = 3.0;        // pixels within this angle of the sun are masked, degrees
  double clip_fraction = 0.98;      // with a clipping plateau, pixels >= this x the clip level are masked
  std::string mask_path;            // optional user mask EXR (R < 0.5 excludes the pixel)
  // One user mask per reference, in the references' order (a day of calibrated photos, each
  // with its own sky segmentation); instead of mask_path.
  std::vector<std::string> mask_paths;
  bool absolute = false;            // references are calibrated: the exposure is fixed at 1
  RobustLoss loss = RobustLoss::kCauchy;
  // Floor of the robust loss's scale, natural-log units (~5%). With the linear start the
  // scale used is max(loss_scale, 2.385 x the MAD-sigma of the least-squares residuals):
  // a sky the model fits only to 10% keeps its worst regions (fit/src/linear_start.h).
  double loss_scale = 0.05;
  // Variable projection before the Ceres polish (fit/src/linear_start.h): g searched with
  // the LUT solved linearly, robust weights annealed; the coarse pyramid levels are then
  // skipped. Off: the coarse-to-fine Ceres solve from the initial preset (the old path).
  bool linear_start = true;
  int linear_width = 128;           // level width of the linear start's g search (pixels; capped at the finest)
  // Run the Ceres polish through the backend after the linear start even when nothing
  // needs it (it always runs with probe samples, or when the render check fails).
  bool polish = false;
  int linear_threads = 2;           // threads of the linear solves (a day's references run two at a time with 1 each)
  // Coarse-to-fine widths of the area-averaged pyramid, last = full fit resolution (pixels).
  // Empty: automatic (64, 128, ... up to the reference width, at most 512).
  std::vector<int> pyramid_widths;
  int max_iterations_per_level = 50;  // Ceres iterations per pyramid level (the polish: its only level)
  double smoothness = 1e-6;         // second-difference prior on the LUT change along sun zenith (rows)
  double prior_weight = 1e-8;       // weight pulling each LUT entry (log) toward the initial preset
  // The weight of the rendered profile's second difference across the LUT columns at the
  // azimuths no fitted pixel reads, in the linear start (fit/src/linear_sky_unseen.cc; one
  // reference and a day alike). The game draws a column at every azimuth; where a masked
  // horizon leaves a column seen at a few, those pixels would set what it draws all round
  // (stripes along the horizon). A sky seen all round gets no such term. Why 1e-4:
  // bench/results/horizon_columns.md. 0: off.
  double unseen_profile = 1e-4;
  bool fit_haziness = true;
  bool fit_overcast = true;         // fit the overcast zenith luminance (weight held, see docs)
  bool numeric_derivatives = false; // baseline for the benchmark: central differences
  // The gray probe (when a reference has samples, see FitSky). Each probed reference's
  // probe residuals together weigh probe_weight times that reference's sky pixels (both
  // are solid-angle / pixel-count normalised squared log errors): why 0.1, and what other
  // values do, in docs/fitting.md "Joint sky and probe fit" and bench/results/probe_weight.md.
  double probe_weight = 0.1;
  int probe_quadrature_width = 128; // lat-long width of the model sky's irradiance quadrature
  bool fit_ground_albedo = true;    // fitted when probe samples face the ground
  double sun_visible_threshold = 0.25;  // the sun's share of the brightest sun-facing samples
  // Skip decisions (fit.json `decisions`), each switchable so the fit-decisions bench suite can measure what
  // it saves (bench/results/fit_decisions.md). Defaults: skip.
  // After the linear start, polish only the finest level (off: the whole pyramid runs).
  bool skip_coarse_levels = true;
  // ffxv-iso: fold the overcast term into the isotropic table, L_z held near 0 (the
  // overcast shape depends on the view elevation only, which that table already spans:
  // the two are not separable). Off: fit L_z there too.
  bool hold_inseparable_overcast = true;
  bool verbose = true;              // progress on stderr
  std::optional<double> time_of_day_h;  // hours, recorded in the preset for export

  bool IsValid(std::string* why) const;
};

}  // namespace skycal::fit
