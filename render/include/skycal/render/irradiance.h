// Predicting the gray diffuse probe (Wood, Forza Horizon 3 skies, GDC: "diffuse probe + key light = this
// value") from the sky model: irradiance on a diffuse ball's surface normals, by direct
// quadrature over a lat-long render and by order-2 spherical harmonics.
//
//   E(n) = integral over the sphere of L(w) max(0, n.w) dw          (lux per channel)
//   ball radiance for a Lambertian albedo rho: rho / pi * E(n)     (cd/m^2 per channel)
//
// Why the sun is analytic: the sun disc (radius ~0.27 deg) covers a fraction of one pixel
// of a 512x256 lat-long (0.7 deg per pixel), so rendered into the image it is aliased:
// its integral depends on where the disc falls on the pixel grid (from zero when it falls
// between pixel centres to several times too much when a centre lands in it). The
// prediction therefore renders the sky WITHOUT the disc and adds the disc's exact
// irradiance E_sun max(0, n.s) (a disc this small is a point light to within
// 1 - cos(0.27 deg) ~ 1e-5 of its cosine factor).
#pragma once
#include <array>
#include <numbers>
#include <vector>

#include "skycal/core/image.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::render {

using Rgb = std::array<double, 3>;
using Dir3 = std::array<double, 3>;

// E(n) by quadrature over every pixel of a full-sphere lat-long (core/latlong.h convention:
// PixelDirection, PixelSolidAngle). Non-finite or negative pixels count as zero.
Rgb IrradianceQuadrature(const ImageRGB& latlong, const Dir3& normal);
// The same for many normals (parallel over normals; `threads` workers, default 2).
std::vector<Rgb> IrradianceQuadrature(const ImageRGB& latlong, const std::vector<Dir3>& normals, int threads = 2);

// Irradiance of the sun as a point light: E_sun max(0, n.s), zero when !visible.
// e_sun_rgb: illuminance at normal incidence (lux per channel); sun_dir, normal: unit.
Rgb SunIrradiance(const Rgb& e_sun_rgb, const Dir3& sun_dir, const Dir3& normal, bool visible);

// Direct-sun illuminance at normal incidence at the ground for a preset and sun direction,
// exactly as the renderer computes it (render/src/resolved_sky.cc):
// sun_illuminance_lux * sun_tint_rgb * SunTransmittance(sun zenith).
Rgb SunIlluminanceAtGround(const Preset& preset, const Dir3& sun_dir);

// Radiance of a Lambertian ball of albedo rho lit by irradiance E: rho / pi * E.
Rgb BallRadiance(const Rgb& irradiance, double albedo);

// ---- Order-2 spherical harmonics (9 coefficients per channel) ----------------------------
// Real SH basis in the project's frame (x, y, z) with +Y up (any orthonormal real basis
// works: the clamped-cosine convolution is rotation invariant per band). Index order:
// (l,m) = (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0), (2,1), (2,2) with
//   Y00 = 1/2 sqrt(1/pi); Y1m = sqrt(3/(4pi)) {y, z, x};
//   Y2-2 = 1/2 sqrt(15/pi) xy, Y2-1 = 1/2 sqrt(15/pi) yz, Y20 = 1/4 sqrt(5/pi) (3z^2 - 1),
//   Y21 = 1/2 sqrt(15/pi) xz, Y22 = 1/4 sqrt(15/pi) (x^2 - y^2).
// Irradiance from radiance coefficients follows R. Ramamoorthi and P. Hanrahan, "An
// Efficient Representation for Irradiance Environment Maps", SIGGRAPH 2001:
// E_lm = A_l L_lm with the clamped-cosine kernel's band constants A0 = pi, A1 = 2pi/3,
// A2 = pi/4. Truncation error for a single directional light of illuminance Phi: the
// order-2 kernel is Phi (3/32 + c/2 + 15/32 c^2), c = n.s, against Phi max(0, c); the
// largest error is 3/32 Phi ~ 0.0298 pi Phi (at c = 0, normals perpendicular to the light),
// then Phi/16 at c = +-1 and -0.0396 Phi at c = +-8/15.
using ShCoefficients = std::array<Rgb, 9>;  // [basis index][channel], radiance coefficients

std::array<double, 9> ShBasis(const Dir3& unit_dir);
// L_lm = sum over pixels of L(w) Y_lm(w) dw (same quadrature as IrradianceQuadrature).
ShCoefficients ProjectSh9(const ImageRGB& latlong);
// E(n) = sum_lm A_l L_lm Y_lm(n).
Rgb ShIrradiance(const ShCoefficients& radiance_sh, const Dir3& normal);
inline constexpr std::array<double, 3> kShClampedCosineBand = {std::numbers::pi, 2.0 * std::numbers::pi / 3.0,
                                                               std::numbers::pi / 4.0};

// n points spread over the unit sphere (Fibonacci / golden-angle spiral), y from
// 1 - 1/n down to -1 + 1/n. n >= 1.
std::vector<Dir3> FibonacciSphere(int n);

struct ProbePrediction {
  Dir3 sun_dir{};                    // unit, toward the sun
  bool sun_visible = false;          // sun above the horizon (y > 0): the analytic term is on
  Rgb sun_illuminance{};             // E_sun at normal incidence, lux per channel
  double albedo = 0.18;
  int width = 0, height = 0;         // the lat-long rendered (sky without the disc)
  GroundMode ground = GroundMode::kLit;
  std::vector<Dir3> normals;
  // Per normal, lux per channel.
  std::vector<Rgb> sky_quadrature;   // sky (and ground) only, by quadrature
  std::vector<Rgb> sky_sh;           // sky (and ground) only, from the SH-9 projection
  std::vector<Rgb> irradiance;       // sky_quadrature + sun term: the prediction
  std::vector<Rgb> irradiance_sh;    // sky_sh + sun term
  std::vector<Rgb> ball_radiance;    // albedo / pi * irradiance, cd/m^2 per channel
  ShCoefficients sh{};               // radiance SH-9 of the sky render (no disc)
  // SH-9 sky irradiance vs quadrature over the normals, relative per channel:
  // |E_sh - E_q| / max(E_q, 1e-3 * max over normals and channels of E_q) (the floor keeps
  // normals that see almost no light, e.g. facing down with a black ground, finite).
  double sh_max_rel_error = 0.0, sh_rms_rel_error = 0.0;
  // The same on the total (sky + sun) irradiance, which is what the probe shows.
  double sh_total_max_rel_error = 0.0, sh_total_rms_rel_error = 0.0;
};

// Renders the preset's sky without the sun disc at width x width/2 with `renderer` (the
// Vulkan backend by default in the CLI), integrates it for every normal (quadrature and
// SH-9) and adds the analytic sun term. Throws skycal::Error on bad input.
ProbePrediction PredictProbe(const Preset& preset, const Dir3& sun_dir, const std::vector<Dir3>& normals, double albedo,
                             SkyRenderer& renderer, int width = 512, GroundMode ground = GroundMode::kLit);

}  // namespace skycal::render
