// Synthetic references for the fit benchmark (the same construction as
// tests/fit_roundtrip_test.cc): the bundled preset as truth, a smooth multiplicative
// perturbation of its LUTs and g as the start.
#pragma once
#include <cmath>
#include <random>
#include <string>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"

namespace skycal::bench {

inline render::Preset TruthPreset(render::ModelVariant variant) {
  render::Preset p = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  p.variant = variant;
  p.haziness_g = 0.76;
  if (variant == render::ModelVariant::kFfxvIso) {
    for (size_t i = 0; i < p.luts.isotropic.size(); ++i) p.luts.isotropic[i] = 0.15f * (p.luts.rayleigh[i] + p.luts.mie[i]);
  }
  return p;
}

inline render::Preset PerturbedStart(const render::Preset& truth, unsigned seed) {
  render::Preset p = truth;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 6.28);
  const int rows = p.luts.grid.n_theta, cols = p.luts.grid.n_gamma;
  for (auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic}) {
    const double a = u(rng), b = u(rng);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        for (int ch = 0; ch < 3; ++ch) {
          float& v = (*t)[(static_cast<size_t>(r) * cols + c) * 3 + ch];
          v = static_cast<float>(v * std::exp(0.2 * std::sin(a + 0.3 * r + 0.2 * c + ch) * std::cos(b + 0.1 * c)));
        }
  }
  p.haziness_g = truth.haziness_g + 0.06;
  return p;
}

inline void WriteSyntheticReference(const std::string& path, const render::Preset& truth, double elevation, double azimuth,
                                    int width) {
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(elevation, azimuth);
  req.width = width;
  req.height = width / 2;
  capture::LatLongFrame f;
  f.radiance = cpu->Render(truth, req);
  f.sun_direction = req.sun_dir;
  capture::WriteLatLongFrame(path, f);
}

}  // namespace skycal::bench
