// The fitted quantities, in the form the optimiser sees them: LUT entries in log space (so
// they stay positive and relative changes are uniform across five orders of magnitude),
// haziness g, log overcast zenith luminance, and one log exposure per reference.
#pragma once
#include <array>
#include <vector>

#include "skycal/render/preset.h"

namespace skycal::fit {

// The lower of the two LUT rows a sun's lookup blends (sun_height: the y of its unit
// direction), clamped so that the row above it exists.
int SunLutRow0(const render::LutGrid& grid, double sun_height);
// The two LUT rows a sun's lookup blends (SunLutRow0 and the row above), true in a mask of
// the grid's rows: what one reference sees of the table.
std::vector<bool> SunLutRows(const render::LutGrid& grid, double sun_height);

struct FitState {
  render::Preset preset;        // everything not fitted (grid, variant, sun, overcast weight)
  int tables = 2;               // 2: Rayleigh, Mie (ffxv); 3: + isotropic (ffxv-iso)
  std::vector<double> log_lut;  // [table][row][col][channel], natural log of cd/m^2 * sr
  double g = 0.8;
  double log_overcast_zenith = 0.0;  // log cd/m^2
  std::vector<double> log_exposure;  // per reference: fitted image = exposure * model
  // Per reference: the sun's illuminance at normal incidence (RGB, model units: lux when
  // the references are absolute), fitted from the gray probe; 0 without one.
  std::vector<std::array<double, 3>> sun_rgb;
  double ground_albedo = 0.1;        // diffuse ground below the horizon (fitted from the probe)
  // Tied rows (one reference): log change per [table][col][channel] applied to both rows
  // around the sun angle (see sky_row_cost.h).
  std::vector<double> log_delta;
  std::vector<int> tied_rows;              // rows whose value is initial + log_delta
  std::vector<double> initial_log_lut;     // u0, from the initial preset

  // Writes initial + log_delta into log_lut for the tied rows, then unties them.
  void ApplyTiedRows();

  size_t DeltaIndex(int table, int col, int ch) const {
    return (static_cast<size_t>(table) * preset.luts.grid.n_gamma + col) * 3 + ch;
  }

  size_t Index(int table, int row, int col, int ch) const {
    const auto& gr = preset.luts.grid;
    return ((static_cast<size_t>(table) * gr.n_theta + row) * gr.n_gamma + col) * 3 + ch;
  }
  // A Rayleigh or Mie table whose largest start entry (at a sun, per channel) is under this
  // share of the other's is vanishing there: under 1% of the start's radiance, its shape shown
  // by nothing in the start's own sky (the Mie at twilight, 1e-4 to 1e-16 of the Rayleigh).
  // The linear start's pull does not pin it (linear_sky.cc) and the columns no pixel sees take
  // its nearest seen column's value, not its change (fit_finish.cc).
  static constexpr double kVanishingTable = 1e-2;
  // The rule above: a table whose largest entry is `largest`, beside the other's `other`.
  static bool Vanishing(double largest, double other) { return largest < kVanishingTable * other; }
  // Initial state from a preset; tables with zeros start at a floor (log of 0 is -inf).
  static FitState FromPreset(const render::Preset& init, render::ModelVariant variant, int references);
  // The rows (rows[row] true: those the fit solves) the start's model leaves dark start flat
  // at the zero entries' floor, every table, in log_lut and initial_log_lut (fit_state.cc).
  void StartDarkRowsFlat(const std::vector<bool>& rows);
  // The model the state describes (floats, as the renderer and the preset files hold it).
  render::Preset ToPreset() const;

 private:
  render::Preset ToPresetUntied() const;
};

}  // namespace skycal::fit
