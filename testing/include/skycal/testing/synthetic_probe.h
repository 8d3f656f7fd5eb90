// A synthetic gray ball under a known sky, sun and ground (tests/probe_fit_test.cc,
// bench/src/fit_probe_suite.cc).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "skycal/capture/probe.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/renderer.h"

namespace skycal::synthetic {

// Probe samples of a ball of `albedo` under the preset's sky and a sun of illuminance e_sun
// (0: behind cloud), on a diffuse ground of albedo ground_albedo lit by that sun and the
// sky: radiance = albedo/pi (E_sky(n) + E_sun max(0, n.s) + ground_albedo (1 - n_y)/2
// (E_sky(up) + E_sun max(0, s_y))) (1 + noise), E_sky by quadrature over a 512x256 render
// without the disc or the ground (finer than the fit's 128x64 quadrature, so a test also
// carries the fit's quadrature error). Normals: the hemisphere facing a camera that looks
// 40 degrees off the sun's azimuth from slightly above; samples with n.s > 0.9 are clipped
// on the photograph and dropped. 20 pixels per sample.
inline std::vector<capture::ProbeSample> ProbeSamplesFor(const render::Preset& preset, const std::array<double, 3>& sun,
                                                         const render::Rgb& e_sun, double albedo, double noise,
                                                         unsigned seed, double ground_albedo = 0.1) {
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = 512;
  req.height = 256;
  req.sun_disc = false;
  req.ground = render::GroundMode::kZero;
  const ImageRGB sky = cpu->Render(preset, req);
  const double az = std::atan2(sun[0], sun[2]) + 40.0 * M_PI / 180.0;
  const std::array<double, 3> to_camera = {std::sin(az), 0.2, std::cos(az)};
  std::vector<render::Dir3> normals;
  for (const auto& n : render::FibonacciSphere(400)) {
    const double facing = n[0] * to_camera[0] + n[1] * to_camera[1] + n[2] * to_camera[2];
    const double ns = n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2];
    if (facing > 0.1 && ns <= 0.9) normals.push_back(n);
  }
  const auto e_sky = render::IrradianceQuadrature(sky, normals);
  const auto e_up = render::IrradianceQuadrature(sky, render::Dir3{0.0, 1.0, 0.0});
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise > 0.0 ? noise : 1.0);
  std::vector<capture::ProbeSample> samples;
  for (size_t i = 0; i < normals.size(); ++i) {
    const auto e = render::SunIrradiance(e_sun, sun, normals[i], true);
    const double h = 0.5 * (1.0 - normals[i][1]);
    capture::ProbeSample smp;
    smp.normal = normals[i];
    smp.pixels = 20;
    for (int c = 0; c < 3; ++c) {
      const double ground = ground_albedo * h * (e_up[c] + e_sun[c] * std::max(0.0, sun[1]));
      smp.radiance[c] = albedo / M_PI * (e_sky[i][c] + e[c] + ground) * (1.0 + (noise > 0.0 ? gauss(rng) : 0.0));
    }
    samples.push_back(smp);
  }
  return samples;
}

}  // namespace skycal::synthetic
