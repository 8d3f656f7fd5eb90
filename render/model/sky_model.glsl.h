// The game's sky model, written once in the GLSL/C++ common subset (rules in
// glsl_compat.h). Included by render/shaders/*.comp and, inside
// skycal::render::SkyModel<Scalar, LutSource>, by the CPU reference and the fit.
//
// Radiance unit: cd/m^2 per channel of scene-linear Rec.709 (the channels' Rec.709
// luminance weights give cd/m^2). Angles in radians. Directions are unit vectors in the
// lat-long frame of core/latlong.h (+Y up).
//
// Sky (Final Fantasy XV, DESIGN.md 1.1, seeds/002):
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
// filtering is bilinear between nodes with clamping at the edges):
//   row = ts / ts_max * (n_theta - 1),   ts in [0, ts_max], ts_max = 108 deg by default
//         (sun 18 deg below the horizon: astronomical twilight ends there);
//   col = sqrt(elevation / (pi/2)) * (n_gamma - 1), elevation = pi/2 - gv in [0, pi/2].
// The square root puts half the columns in the lowest 15 degrees of elevation, where
// the sky changes fastest (Bruneton & Neyret 2008 use the same idea for their LUTs).

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
  Scalar lut_theta_max;         // ts_max, radians
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

// Elevation of a unit direction above the horizon, radians in [-pi/2, pi/2].
Scalar elevation_of(vec3 d) {
  return atan(d.y, sqrt(d.x * d.x + d.z * d.z));
}

// Continuous LUT coordinates (row, col) in texel units.
struct LutCoord {
  int row0;
  int col0;
  Scalar frow;  // weight of row0 + 1
  Scalar fcol;  // weight of col0 + 1
};

LutCoord lut_coord(Scalar sun_zenith, Scalar view_elevation, SkyParams p) {
  Scalar r = clamp(sun_zenith / p.lut_theta_max, Scalar(0.0), Scalar(1.0)) * Scalar(p.lut_n_theta - 1);
  Scalar e = clamp(view_elevation / Scalar(0.5 * SC_PI), Scalar(0.0), Scalar(1.0));
  Scalar c = sqrt(e) * Scalar(p.lut_n_gamma - 1);
  LutCoord lc;
  lc.row0 = clamp(floor_to_int(r), 0, p.lut_n_theta - 2);
  lc.col0 = clamp(floor_to_int(c), 0, p.lut_n_gamma - 2);
  lc.frow = r - Scalar(lc.row0);
  lc.fcol = c - Scalar(lc.col0);
  return lc;
}

// Bilinear filtering between the four surrounding nodes (what a GPU sampler does, but
// with exact weights: Vulkan lets samplers quantise weights to subTexelPrecisionBits,
// 8 bits on lavapipe, which would cost ~0.4% and make derivatives inconsistent).
vec3 lut_bilinear(int lut, LutCoord lc) {
  vec3 t00 = lut_texel(lut, lc.row0, lc.col0);
  vec3 t01 = lut_texel(lut, lc.row0, lc.col0 + 1);
  vec3 t10 = lut_texel(lut, lc.row0 + 1, lc.col0);
  vec3 t11 = lut_texel(lut, lc.row0 + 1, lc.col0 + 1);
  return mix(mix(t00, t01, lc.fcol), mix(t10, t11, lc.fcol), lc.frow);
}

// Sun zenith angle, radians in [0, pi].
Scalar sun_zenith_of(SkyParams p) {
  return atan(sqrt(p.sun_dir.x * p.sun_dir.x + p.sun_dir.z * p.sun_dir.z), p.sun_dir.y);
}

// Sky radiance for a view direction at or above the horizon, without the sun disc.
vec3 sky_radiance(vec3 view, SkyParams p) {
  vec3 diff = view - p.sun_dir;
  Scalar one_minus_mu = Scalar(0.5) * dot(diff, diff);
  Scalar mu = Scalar(1.0) - one_minus_mu;
  Scalar elevation = elevation_of(view);
  LutCoord lc = lut_coord(sun_zenith_of(p), elevation, p);
  vec3 lut = lut_bilinear(LUT_RAYLEIGH, lc) * phase_rayleigh(mu) +
             lut_bilinear(LUT_MIE, lc) * phase_cornette_shanks(mu, one_minus_mu, p.haziness_g);
  if (p.isotropic_weight > Scalar(0.0)) {
    lut = lut + lut_bilinear(LUT_ISOTROPIC, lc) * (p.isotropic_weight * Scalar(1.0 / (4.0 * SC_PI)));
  }
  // sin(elevation) of a unit vector is its y component.
  Scalar overcast = p.overcast_zenith * (Scalar(1.0) + Scalar(2.0) * max(view.y, Scalar(0.0))) / Scalar(3.0);
  return mix(lut, vec3(overcast, overcast, overcast), p.overcast_weight);
}

// Sun disc radiance (0 outside the disc).
vec3 sun_disc_radiance(vec3 view, SkyParams p) {
  vec3 diff = view - p.sun_dir;
  Scalar one_minus_mu = Scalar(0.5) * dot(diff, diff);
  if (one_minus_mu >= p.sun_one_minus_cos_radius) return vec3(Scalar(0.0));
  // Angular distance r = 2 asin(|v - s| / 2), exact and well conditioned near 0.
  Scalar r = Scalar(2.0) * asin(Scalar(0.5) * sqrt(dot(diff, diff)));
  Scalar rho = min(r / p.sun_radius, Scalar(1.0));
  Scalar cos_limb = sqrt(max(Scalar(1.0) - rho * rho, Scalar(0.0)));
  return p.sun_centre_radiance * (Scalar(1.0) - p.sun_limb_u * (Scalar(1.0) - cos_limb));
}

// Everything the renderer shows for one view direction.
vec3 radiance(vec3 view, SkyParams p) {
  if (view.y < Scalar(0.0)) return p.ground_radiance;
  return sky_radiance(view, p) + sun_disc_radiance(view, p);
}

// Pixel centre (x, y) of a width x height lat-long image to a unit direction, following
// OpenEXR's envmap LatLong convention (core/latlong.h): latitude +pi/2 at row 0,
// longitude +pi at column 0 and -pi at column width - 1.
vec3 latlong_direction(int x, int y, int width, int height) {
  Scalar lat = Scalar(-SC_PI) * (Scalar(y) / Scalar(height - 1) - Scalar(0.5));
  Scalar lon = Scalar(-2.0 * SC_PI) * (Scalar(x) / Scalar(width - 1) - Scalar(0.5));
  Scalar cl = cos(lat);
  return vec3(sin(lon) * cl, sin(lat), cos(lon) * cl);
}
