// Presets for tests: random LUTs (seeded, reproducible) on the default grid.
#pragma once
#include <cmath>
#include <random>

#include "skycal/render/preset.h"

namespace skycal::testing {

// Random LUTs shaped like real ones: a random smooth field spanning [lo, hi]
// (cd/m^2 * sr) times per-texel jitter of up to 2x between neighbours. (Real LUTs change
// by a few percent between nodes; 2x is a deliberately rough stress for the filtering
// and coordinate precision.) Sun transmittance uniform in [0.2, 1].
inline render::Preset RandomPreset(unsigned seed, render::ModelVariant variant, double lo = 10.0, double hi = 1e4) {
  render::Preset p;
  p.name = "random-" + std::to_string(seed);
  p.variant = variant;
  p.luts.Resize(render::LutGrid{});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int rows = p.luts.grid.n_theta, cols = p.luts.grid.n_gamma;
  for (auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic}) {
    const double fr = 0.5 + 2.5 * unit(rng), fc = 0.5 + 2.5 * unit(rng), ph = 6.28 * unit(rng);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        for (int ch = 0; ch < 3; ++ch) {
          const double smooth = 0.5 + 0.5 * std::sin(fr * r / rows * 6.28 + fc * c / cols * 6.28 + ph + ch);
          const double jitter = 0.35 * (2.0 * unit(rng) - 1.0);  // ln 2 / 2: neighbours within 2x
          const double v = std::exp(std::log(lo) + smooth * (std::log(hi) - std::log(lo)) * 0.9 + jitter);
          (*t)[(static_cast<size_t>(r) * cols + c) * 3 + ch] = static_cast<float>(v);
        }
      }
    }
  }
  std::uniform_real_distribution<double> tr(0.2, 1.0);
  for (float& v : p.luts.sun_transmittance) v = static_cast<float>(tr(rng));
  return p;
}

}  // namespace skycal::testing
