#include "fit_state.h"

#include <algorithm>
#include <cmath>

namespace skycal::fit {
namespace {

// Floor for zero entries: 5% of the mean of the Rayleigh and Mie tables, a neutral start
// the data moves quickly (log space), and never -inf.
double ZeroFloor(const render::Preset& p) {
  const size_t table = p.luts.table_size();
  double mean = 0.0;
  for (size_t i = 0; i < table; ++i) mean += p.luts.rayleigh[i] + p.luts.mie[i];
  mean /= 2.0 * static_cast<double>(table);
  return std::max(0.05 * mean, 1e-6);
}

// Whether the preset's LUT row is partly dark: a Rayleigh or Mie entry zero (the sun far
// enough below the horizon that the Earth's shadow cuts its single scattering).
bool DarkRow(const render::Preset& p, int row) {
  const size_t row_size = static_cast<size_t>(p.luts.grid.n_gamma) * 3, begin = row * row_size;
  for (size_t i = begin; i < begin + row_size; ++i)
    if (!(p.luts.rayleigh[i] > 0.0f) || !(p.luts.mie[i] > 0.0f)) return true;
  return false;
}

}  // namespace

int SunLutRow0(const render::LutGrid& grid, double sun_height) {
  return std::clamp(static_cast<int>(std::floor(render::LutRowPosition(grid, sun_height))), 0, grid.n_theta - 2);
}

std::vector<bool> SunLutRows(const render::LutGrid& grid, double sun_height) {
  std::vector<bool> rows(grid.n_theta, false);
  const int r0 = SunLutRow0(grid, sun_height);
  rows[r0] = rows[r0 + 1] = true;
  return rows;
}

FitState FitState::FromPreset(const render::Preset& init, render::ModelVariant variant, int references) {
  FitState s;
  s.preset = init;
  s.preset.variant = variant;
  s.tables = variant == render::ModelVariant::kFfxvIso ? 3 : 2;
  const size_t table = init.luts.table_size();
  if (s.preset.luts.isotropic.size() != table) s.preset.luts.isotropic.assign(table, 0.0f);
  s.log_lut.assign(3 * table, 0.0);
  const double floor_value = ZeroFloor(init);
  const std::vector<float>* src[3] = {&s.preset.luts.rayleigh, &s.preset.luts.mie, &s.preset.luts.isotropic};
  for (int t = 0; t < 3; ++t) {
    for (size_t i = 0; i < table; ++i) {
      const double v = (*src[t])[i];
      s.log_lut[t * table + i] = std::log(v > 0.0 ? v : floor_value);
    }
  }
  s.g = init.haziness_g;
  s.log_overcast_zenith = std::log(std::max(init.overcast_zenith_cd_m2, 1e-6));
  s.log_exposure.assign(references, 0.0);
  s.sun_rgb.assign(references, {0.0, 0.0, 0.0});
  s.ground_albedo = init.ground_albedo;
  s.log_delta.assign(static_cast<size_t>(3) * init.luts.grid.n_gamma * 3, 0.0);
  s.initial_log_lut = s.log_lut;
  return s;
}

// A fitted row the start's model leaves partly dark: its zeros took the floor, and the tiny
// entries beside them (1e-3 to 1e-16 of it in the bundled presets, sun 9-14 deg down) made a
// cliff of many orders of magnitude between neighbouring columns. The fit keeps the start's
// shape where no pixel looks (the lowest columns under a ridge at twilight), and the cliff drew
// a dark band along the horizon under the glow. Rows the fit does not solve keep the preset's
// values (they are written out as they came).
void FitState::StartDarkRowsFlat(const std::vector<bool>& rows) {
  const auto& grid = preset.luts.grid;
  const size_t table = preset.luts.table_size(), row_size = static_cast<size_t>(grid.n_gamma) * 3;
  const double log_floor = std::log(ZeroFloor(preset));
  for (int row = 0; row < grid.n_theta; ++row) {
    if (row >= static_cast<int>(rows.size()) || !rows[row] || !DarkRow(preset, row)) continue;
    for (int t = 0; t < 3; ++t) {
      const auto begin = static_cast<std::ptrdiff_t>(t * table + row * row_size);
      std::fill(log_lut.begin() + begin, log_lut.begin() + begin + row_size, log_floor);
      std::fill(initial_log_lut.begin() + begin, initial_log_lut.begin() + begin + row_size, log_floor);
    }
  }
}

void FitState::ApplyTiedRows() {
  const auto& g = preset.luts.grid;
  for (int row : tied_rows)
    for (int t = 0; t < 3; ++t)
      for (int col = 0; col < g.n_gamma; ++col)
        for (int ch = 0; ch < 3; ++ch) log_lut[Index(t, row, col, ch)] = initial_log_lut[Index(t, row, col, ch)] + log_delta[DeltaIndex(t, col, ch)];
  tied_rows.clear();
  std::fill(log_delta.begin(), log_delta.end(), 0.0);
}

render::Preset FitState::ToPreset() const {
  FitState applied = *this;
  applied.ApplyTiedRows();
  return applied.ToPresetUntied();
}

render::Preset FitState::ToPresetUntied() const {
  render::Preset p = preset;
  const size_t table = p.luts.table_size();
  std::vector<float>* dst[3] = {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic};
  for (int t = 0; t < 3; ++t) {
    for (size_t i = 0; i < table; ++i) (*dst[t])[i] = t < tables ? static_cast<float>(std::exp(log_lut[t * table + i])) : 0.0f;
  }
  p.haziness_g = g;
  p.ground_albedo = ground_albedo;
  p.overcast_zenith_cd_m2 = std::exp(log_overcast_zenith);
  return p;
}

}  // namespace skycal::fit
