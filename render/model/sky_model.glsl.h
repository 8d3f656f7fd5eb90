// The game's sky model, written once in the GLSL/C++ common subset (rules in
// glsl_compat.h). Included by render/shaders/*.comp and, inside
// skycal::render::SkyModel<Scalar, LutSource>, by the CPU reference and the fit.
//
// Radiance unit: cd/m^2 per channel of scene-linear Rec.709 (the channels' Rec.709
// luminance weights give cd/m^2). Angles in radians. Directions are unit vectors in the
// lat-long frame of core/latlong.h (+Y up).
//
// Sky (Miyamoto & Driancourt, "Rendering Techniques of Final Fantasy XV", SIGGRAPH 2016):
//   L_lut = LutR(ts, gv) * phaseR(mu) + LutM(ts, gv) * phaseM(mu, g) [+ LutI(ts, gv) / (4 pi)]
// ts = sun zenith angle, gv = view zenith angle, mu = cos(view, sun). The LUTs hold
// "radiance per unit phase function" (cd/m^2 * sr); each phase function integrates to 1
// over the sphere, so the LUT value is what the term would contribute if it scattered
// isotropically. The third, isotropic term is the `ffxv-iso` variant.
//   L_sky = mix(L_lut, L_overcast, overcast_weight),
//   L_overcast = L_zenith * (1 + 2 sin(elevation)) / 3 (CIE standard overcast sky, grey).
// Sun disc: centre radiance L0, linear limb darkening I(r)/I(0) = 1 - u (1 - cos_limb),
// cos_limb = sqrt(1 - (r / R)^2) for angular distance r from the sun centre, radius R.
// Below the horizon (view y < 0): a constant ground radiance chosen by the host.
//
// LUT parameterisation (node-centred: texel (row, col) sits exactly on a grid node, and
// filtering is bilinear between nodes with clamping at the edges). Both coordinates are
// formed from direction components without inverse trigonometry:
//   row = (1 - cos ts) / (1 - cos ts_max) * (n_theta - 1),  ts_max = 108 deg by default
//         (the sun 18 deg below the horizon: astronomical twilight ends there). Linear in
//         the sun's height sun.y, so rows crowd toward sunrise/sunset (2 deg apart at the
//         horizon, 15 deg near the zenith) where the sky changes fastest;
//   col = sqrt(sin(elevation)) * (n_gamma - 1) = sqrt(view.y) * (n_gamma - 1): half the
//         columns cover the lowest 14.5 deg of elevation, where the sky changes fastest
//         (Bruneton & Neyret 2008 concentrate their LUTs near the horizon the same way).
// Why no atan/asin: GPUs (and lavapipe) implement them with ~1e-6 absolute error, which
// the sqrt mapping near the horizon would amplify; sun.y and view.y are exact to rounding.

SC_CONST(SC_PI, 3.14159265358979323846)
SC_CONST_INT(LUT_RAYLEIGH, 0)
SC_CONST_INT(LUT_MIE, 1)
SC_CONST_INT(LUT_ISOTROPIC, 2)

struct SkyParams {
  vec3 sun_dir;                 // unit vector toward the sun centre
  Scalar haziness_g;            // Cornette-Shanks asymmetry, [0, 1)
  Scalar isotropic_weight;      // 1 for ffxv-iso, 0 for ffxv
  Scalar overcast_weight;       // [0, 1]
  Scalar overcast_zenith;       // cd/m^2
  Scalar sun_one_minus_cos_radius;  // 1 - cos(R), computed as 2 sin^2(R/2) on the host
  Scalar sun_radius;            // R, radians
  Scalar sun_limb_u;            // linear limb-darkening coefficient, [0, 1]
  vec3 sun_centre_radiance;     // L0, cd/m^2 (0 switches the disc off)
  vec3 ground_radiance;         // cd/m^2, used for view directions below the horizon
  Scalar lut_one_minus_cos_theta_max;  // 1 - cos(ts_max), ts_max = last LUT row's sun zenith
  int lut_n_theta;              // rows
  int lut_n_gamma;              // columns
};

// Rayleigh phase, normalised: 3 / (16 pi) (1 + mu^2).
Scalar phase_rayleigh(Scalar mu) {
  return Scalar(3.0 / (16.0 * SC_PI)) * (Scalar(1.0) + mu * mu);
}

// Cornette-Shanks phase, normalised:
//   3 / (8 pi) * (1 - g^2) / (2 + g^2) * (1 + mu^2) / (1 + g^2 - 2 g mu)^1.5.
// The denominator is evaluated as (1 - g)^2 + 2 g (1 - mu) with 1 - mu passed in from
// |v - s|^2 / 2: for g near 1 and mu near 1 the textbook form cancels catastrophically
// in float (1e-4 from differences of numbers near 2).
Scalar phase_cornette_shanks(Scalar mu, Scalar one_minus_mu, Scalar g) {
  Scalar one_minus_g = Scalar(1.0) - g;
  Scalar d = one_minus_g * one_minus_g + Scalar(2.0) * g * one_minus_mu;
  Scalar norm = Scalar(3.0 / (8.0 * SC_PI)) * (Scalar(1.0) - g * g) / (Scalar(2.0) + g * g);
  return norm * (Scalar(1.0) + mu * mu) / (d * sqrt(d));
}

// LUT coordinates, split into the row (sun) part, uniform over a frame, and the column
// (view) part, per pixel.
struct LutRow {
  int row0;
  Scalar frow;  // weight of row0 + 1
};
struct LutCol {
  int col0;
  Scalar fcol;  // weight of col0 + 1
};

// sun_height = cos(sun zenith) = sun.y.
LutRow lut_row(Scalar sun_height, SkyParams p) {
  Scalar r = clamp((Scalar(1.0) - sun_height) / p.lut_one_minus_cos_theta_max, Scalar(0.0), Scalar(1.0)) *
             Scalar(p.lut_n_theta - 1);
  LutRow lr;
  lr.row0 = clamp(floor_to_int(r), 0, p.lut_n_theta - 2);
  lr.frow = r - Scalar(lr.row0);
  return lr;
}

// view_height = sin(view elevation) = view.y.
LutCol lut_col(Scalar view_height, SkyParams p) {
  Scalar c = sqrt(clamp(view_height, Scalar(0.0), Scalar(1.0))) * Scalar(p.lut_n_gamma - 1);
  LutCol lc;
  lc.col0 = clamp(floor_to_int(c), 0, p.lut_n_gamma - 2);
  lc.fcol = c - Scalar(lc.col0);
  return lc;
}

// Bilinear filtering between the four surrounding nodes, rows first: what a GPU sampler
// computes, but with exact weights (Vulkan lets samplers quantise weights to
// subTexelPrecisionBits, 8 bits on lavapipe: ~0.4% error and inconsistent derivatives).
// lut_column_texel(lut, row0, frow, col) is the backend's hook: the LUT at the sun's row
// position, interpolated between rows row0 and row0 + 1 with weight frow, at node column
// col. The C++ side interpolates the rows itself; the shaders read a per-frame slice the
// host interpolated once in double (the row position is the same for every pixel).
vec3 lut_filtered(int lut, LutRow lr, LutCol lc) {
  vec3 a = lut_column_texel(lut, lr.row0, lr.frow, lc.col0);
  vec3 b = lut_column_texel(lut, lr.row0, lr.frow, lc.col0 + 1);
  return mix(a, b, lc.fcol);
}

// Sky radiance for a view direction at or above the horizon, without the sun disc.
vec3 sky_radiance(vec3 view, SkyParams p) {
  vec3 diff = view - p.sun_dir;
  Scalar one_minus_mu = Scalar(0.5) * dot(diff, diff);
  Scalar mu = Scalar(1.0) - one_minus_mu;
  LutRow lr = lut_row(p.sun_dir.y, p);
  LutCol lc = lut_col(view.y, p);
  vec3 lut = lut_filtered(LUT_RAYLEIGH, lr, lc) * phase_rayleigh(mu) +
             lut_filtered(LUT_MIE, lr, lc) * phase_cornette_shanks(mu, one_minus_mu, p.haziness_g);
  if (p.isotropic_weight > Scalar(0.0)) {
    lut = lut + lut_filtered(LUT_ISOTROPIC, lr, lc) * (p.isotropic_weight * Scalar(1.0 / (4.0 * SC_PI)));
  }
  // sin(elevation) of a unit vector is its y component.
  Scalar overcast = p.overcast_zenith * (Scalar(1.0) + Scalar(2.0) * max(view.y, Scalar(0.0))) / Scalar(3.0);
  return mix(lut, vec3(overcast, overcast, overcast), p.overcast_weight);
}

// Sun disc radiance (0 outside the disc).
vec3 sun_disc_radiance(vec3 view, SkyParams p) {
  vec3 diff = view - p.sun_dir;
  Scalar one_minus_mu = Scalar(0.5) * dot(diff, diff);
  // Squared angular distance r^2 from |v - s|^2 = 2 (1 - cos r) = r^2 - r^4/12 + ...:
  // r^2 = d2 (1 + d2 / 12), relative error < 1e-7 inside a 5 deg disc, no asin. The disc
  // is evaluated branch-free and masked: on SIMD CPUs (lavapipe) a divergent early return
  // cost more than the arithmetic.
  Scalar d2 = dot(diff, diff);
  Scalar r2 = d2 * (Scalar(1.0) + d2 / Scalar(12.0));
  Scalar rho2 = min(r2 / (p.sun_radius * p.sun_radius), Scalar(1.0));
  Scalar cos_limb = sqrt(Scalar(1.0) - rho2);
  Scalar inside = one_minus_mu < p.sun_one_minus_cos_radius ? Scalar(1.0) : Scalar(0.0);
  return p.sun_centre_radiance * (inside * (Scalar(1.0) - p.sun_limb_u * (Scalar(1.0) - cos_limb)));
}

// Everything the renderer shows for one view direction.
vec3 radiance(vec3 view, SkyParams p) {
  vec3 sky = sky_radiance(view, p) + sun_disc_radiance(view, p);
  return view.y < Scalar(0.0) ? p.ground_radiance : sky;
}

#include "latlong.glsl.h"
