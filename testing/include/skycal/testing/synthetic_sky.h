// Synthetic references, shared by tests/fit_roundtrip_test.cc and bench/src/fit_probe_suite.cc: the
// bundled preset as truth, a smooth multiplicative perturbation of its LUTs and g as the
// start, references rendered by the CPU reference with optional noise and outliers.
#pragma once
#include <cmath>
#include <random>
#include <string>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"

namespace skycal::synthetic {

// g = 0.76; for ffxv-iso a multiple-scattering-like isotropic term of 15% of the
// single-scattering tables.
inline render::Preset TruthPreset(render::ModelVariant variant) {
  render::Preset p = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  p.variant = variant;
  p.haziness_g = 0.76;
  if (variant == render::ModelVariant::kFfxvIso) {
    for (size_t i = 0; i < p.luts.isotropic.size(); ++i) p.luts.isotropic[i] = 0.15f * (p.luts.rayleigh[i] + p.luts.mie[i]);
  }
  return p;
}

// Every LUT entry times exp(amplitude * smooth field in [-1, 1]); g + dg.
inline render::Preset PerturbedStart(const render::Preset& truth, unsigned seed, double amplitude = 0.2, double dg = 0.06) {
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
          v = static_cast<float>(v * std::exp(amplitude * std::sin(a + 0.3 * r + 0.2 * c + ch) * std::cos(b + 0.1 * c)));
        }
  }
  p.haziness_g = truth.haziness_g + dg;
  return p;
}

// Renders the truth (sun disc on) to a lat-long EXR with its sunDirection. noise: relative
// Gaussian per channel; outliers: fraction of pixels multiplied by 0.2x .. 5x (a bird, a
// cloud, a lamp).
inline void WriteSyntheticReference(const std::string& path, const render::Preset& truth, double elevation, double azimuth,
                                    int width, double noise = 0.0, double outliers = 0.0, unsigned seed = 1) {
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(elevation, azimuth);
  req.width = width;
  req.height = width / 2;
  capture::LatLongFrame f;
  f.radiance = cpu->Render(truth, req);
  if (noise > 0.0 || outliers > 0.0) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss(0.0, noise > 0.0 ? noise : 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (size_t i = 0; i < f.radiance.pixels.size(); i += 3) {
      const bool outlier = unit(rng) < outliers;
      const double o = outlier ? std::exp(std::log(5.0) * (2.0 * unit(rng) - 1.0)) : 1.0;
      for (int c = 0; c < 3; ++c) {
        const double n = noise > 0.0 ? gauss(rng) : 0.0;
        f.radiance.pixels[i + c] = static_cast<float>(f.radiance.pixels[i + c] * o * (1.0 + n));
      }
    }
  }
  f.sun_direction = req.sun_dir;
  capture::WriteLatLongFrame(path, f);
}

}  // namespace skycal::synthetic
