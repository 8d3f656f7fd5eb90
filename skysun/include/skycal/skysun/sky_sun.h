// The sun's direction from the sky itself, for photos whose disc is hidden (cloud, haze,
// twilight with the sun below the horizon) and capture::DetectSun finds no peak.
//
// Method (after Lalonde, Efros, Narasimhan, "Estimating natural illumination from a single
// outdoor image", ICCV 2009, who locate the sun from the sky's luminance gradients; here with
// the CIE general sky, CIE S 011/E:2003 = ISO 15469:2004, as the luminance model):
//   1. The caller's sky pixels above the horizon are binned into cells of `cell_deg`; each
//      cell holds the solid-angle weighted mean of ln Y (Rec.709 luminance) and its direction.
//   2. For every candidate sun on a coarse grid (elevation `min_elevation_deg`..90, the sun
//      below the horizon allowed) and every model, ln Y is fitted by linear least squares in
//      closed form; the cost is the weighted RMS of the ln residual (the "log RMSE"). The
//      models (Options::gradation): each CIE indicatrix f(chi) with a free polynomial
//      gradation in sin(elevation) (default), or each CIE type's phi(Z) f(chi) with a free
//      scale.
//   3. The best candidate is refined on finer local grids.
//   4. The uncertainty is the largest angle between the best direction and any candidate
//      whose cost is within the tolerance (see Options) of the best, at least the finest
//      step. The CIE indicatrix without a sun term (group 1, types 1, 3, 5: uniform in
//      azimuth) fits every direction alike, so an overcast sky gets an uncertainty near
//      180 deg.
// The disc itself (and the aureole a lens flares) should be left out of the mask by the
// caller: the CIE indicatrix does not model the disc.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::skysun {

struct SkySunOptions {
  // Path of the CIE general sky table; empty: refsky::DefaultCieCsvPath().
  std::string cie_csv_path;
  // The gradation (the luminance's dependence on elevation alone). kCie: each CIE type's
  // phi(Z) with a free scale (15 models). kPolynomial: a free polynomial of degree
  // polynomial_degree in sin(elevation), with each CIE indicatrix f(chi) (6 models): the
  // sun is placed by the sky's structure relative to the sun only, so a gradation the CIE
  // types lack (strong horizon brightening, haze, lens vignetting) does not pull it.
  enum class Gradation { kCie, kPolynomial };
  Gradation gradation = Gradation::kPolynomial;
  int polynomial_degree = 3;
  // Side of the cells the sky pixels are averaged into (deg). Smaller is slower.
  double cell_deg = 3.0;
  // Cells holding less than this fraction of a full cell's solid angle are dropped
  // (horizon and mask edges).
  double min_cell_fill = 0.25;
  // At least this many cells (sky above the horizon) or the fit is refused.
  int min_cells = 30;
  // Lowest candidate sun elevation (deg); civil twilight ends at -6 deg.
  double min_elevation_deg = -15.0;
  // Coarse grid step (deg) over the whole sphere (elevation and azimuth).
  double coarse_step_deg = 5.0;
  // Refinement: two local grids, +-coarse_step at refine_step, then +-refine_step at
  // final_step (deg).
  double refine_step_deg = 1.0;
  double final_step_deg = 0.25;
  // Candidates within tolerance: cost <= best (1 + relative_tolerance) + absolute_tolerance
  // (cost = log RMSE, ln units). The best cost stands for the residual's sigma; for
  // N_eff independent residuals a 68% region of the two direction parameters is
  // delta chi^2 = 2.3, i.e. RMSE ratio 1 + 2.3 / (2 N_eff). Sky residuals (clouds, lens
  // falloff, model misfit) are strongly correlated, so N_eff is tens, not the cell count:
  // relative_tolerance 0.05 is N_eff = 23. absolute_tolerance is the floor for a perfect fit
  // (an HDR merge's noise, about 1% in luminance).
  double relative_tolerance = 0.05;
  double absolute_tolerance = 0.01;
  // Pixels with a channel >= clip_value are left out (a clamped sensor); 0: no clip test.
  double clip_value = 0.0;
  // EstimateSunFromSky refuses (returns nothing) above this uncertainty (deg).
  double max_uncertainty_deg = 25.0;

  // Empty when usable; otherwise names the first bad field and its value, e.g.
  // "SkySunOptions::cell_deg = 0 must be in (0, 30]".
  std::string Invalid() const;
  bool IsValid(std::string* why) const;
};

struct SkySunEstimate {
  std::array<double, 3> direction{};  // unit vector toward the sun (core/latlong.h, +Y up)
  double elevation_deg = 0.0;         // may be negative (twilight)
  double azimuth_deg = 0.0;           // longitude of core/latlong.h, degrees
  int sky_type = 0;                   // CIE type 1..15 of the best fit (kPolynomial: the first type of
                                      // its indicatrix group)
  double log_rmse = 0.0;              // weighted RMS of ln(L / model) over the cells
  double log_scale = 0.0;             // kCie: ln s of L = s phi(Z) f(chi) (L in the image's units);
                                      // kPolynomial: the polynomial's constant term
  double uncertainty_deg = 0.0;       // largest angle to a candidate within tolerance
  double elevation_uncertainty_deg = 0.0;  // largest |elevation difference| among them
  double azimuth_uncertainty_deg = 0.0;    // largest |azimuth difference| among them (deg of azimuth)
  bool elevation_at_bound = false;    // the best lies at Options::min_elevation_deg (no interior minimum)
  int cells = 0;                      // sky cells fitted
  int candidates = 0;                 // candidate directions evaluated
  int candidates_within_tolerance = 0;
};

// Fits the sun direction to the sky of a lat-long frame. `sky_mask` is width * height
// values, >= 0.5 is sky (empty: every pixel above the horizon). Only pixels above the horizon
// with finite, positive luminance (and under Options::clip_value) count. Throws
// skycal::Error for invalid options, a mask of the wrong size, or fewer than
// Options::min_cells usable cells.
SkySunEstimate FitSunFromSky(const ImageRGB& latlong, const std::vector<float>& sky_mask, const SkySunOptions& options);

// The cost (log RMSE of the best model) of one given sun, e.g. one from the time and place
// (capture/solar_position.h), to compare with the estimate's; *sky_type (may be null) gets
// the model's CIE type. Same errors as FitSunFromSky.
double SkyFitCostAt(const ImageRGB& latlong, const std::vector<float>& sky_mask, const SkySunOptions& options,
                    const std::array<double, 3>& sun, int* sky_type = nullptr);

// FitSunFromSky, refusing (nothing, with the reason in *why) when the uncertainty is over
// Options::max_uncertainty_deg (a sky without azimuthal structure does not place a sun) or
// the best sun lies on the lowest elevation searched (the cost still falls below it: a
// sky the models do not describe, not a located sun).
std::optional<SkySunEstimate> EstimateSunFromSky(const ImageRGB& latlong, const std::vector<float>& sky_mask,
                                                 const SkySunOptions& options, std::string* why);

}  // namespace skycal::skysun
