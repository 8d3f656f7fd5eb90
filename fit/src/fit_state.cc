#include "fit_state.h"

#include <algorithm>
#include <cmath>

namespace skycal::fit {

FitState FitState::FromPreset(const render::Preset& init, render::ModelVariant variant, int references) {
  FitState s;
  s.preset = init;
  s.preset.variant = variant;
  s.tables = variant == render::ModelVariant::kFfxvIso ? 3 : 2;
  const size_t table = init.luts.table_size();
  if (s.preset.luts.isotropic.size() != table) s.preset.luts.isotropic.assign(table, 0.0f);
  s.log_lut.assign(3 * table, 0.0);
  // Floor for zero entries: 5% of the mean of the Rayleigh and Mie tables, a neutral start
  // the data moves quickly (log space), and never -inf.
  double mean = 0.0;
  for (size_t i = 0; i < table; ++i) mean += init.luts.rayleigh[i] + init.luts.mie[i];
  mean /= 2.0 * static_cast<double>(table);
  const double floor_value = std::max(0.05 * mean, 1e-6);
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
