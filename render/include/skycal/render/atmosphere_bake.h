// Offline, physically based baker for the sky model's LUTs (render/model/sky_model.glsl.h).
//
// Final Fantasy XV generated its LUTs offline by least-squares fitting to ray-traced
// skies (Miyamoto & Driancourt, SIGGRAPH 2016). This baker does the ray tracing for a clear, single-
// scattering Earth atmosphere and factors the phase functions out, which is what the
// bundled default preset ships with (the fit then refines those tables against photos).
//
// Atmosphere: a spherical shell between the planet radius and the top radius, with
//   - Rayleigh scattering, density exp(-h / H_R) (no absorption);
//   - Mie scattering and extinction, density exp(-h / H_M);
//   - ozone absorption (no scattering), a tent profile: 1 at the centre altitude, falling
//     linearly to 0 half a width below and above it.
// Default constants are those of Bruneton's 2017 "precomputed_atmospheric_scattering"
// demo (demo.cc), which in turn takes the Rayleigh, Mie and ozone coefficients from
// Hillaire 2020, "A Scalable and Production Ready Sky and Atmosphere Rendering
// Technique" (EGSR 2020), table 1: Earth, 6360 km radius, 60 km thick, ozone between
// 10 km and 40 km peaking at 25 km.
//
// Units: lengths in metres, coefficients in 1/m at density 1 (sea level for Rayleigh and
// Mie, the tent's peak for ozone), illuminance in lux. The sun is white: every channel of
// scene-linear Rec.709 gets sun_illuminance_lux, so LUT values are in lux = cd/m^2 * sr
// and the model's radiance comes out in cd/m^2.
#pragma once
#include <array>
#include <string>

#include "skycal/render/preset.h"

namespace skycal::render {

struct AtmosphereOptions {
  // Geometry.
  double planet_radius_m = 6360e3;    // m, Bruneton 2017 kBottomRadius
  double atmosphere_top_m = 6420e3;   // m, radius (from the planet centre) of the atmosphere's top
                                      // boundary: 60 km thick (Bruneton 2017 kTopRadius)
  double observer_altitude_m = 200.0; // m above the planet surface; must lie below the top

  // Rayleigh (air molecules): scattering only. Red, green, blue channels at 680, 550,
  // 440 nm in Bruneton's demo; the values are Hillaire 2020's.
  std::array<double, 3> rayleigh_scattering_per_m = {5.802e-6, 13.558e-6, 33.1e-6};  // 1/m at h = 0
  double rayleigh_scale_height_m = 8000.0;                                          // m

  // Mie (aerosols): grey. Extinction = scattering + absorption (4.40e-7 1/m absorption in
  // Hillaire 2020), so mie_extinction_per_m >= mie_scattering_per_m.
  double mie_scattering_per_m = 3.996e-6;  // 1/m at h = 0
  double mie_extinction_per_m = 4.440e-6;  // 1/m at h = 0
  double mie_scale_height_m = 1200.0;      // m

  // Ozone: absorption only, tent profile (Bruneton 2017's two linear density layers).
  std::array<double, 3> ozone_absorption_per_m = {0.650e-6, 1.881e-6, 0.085e-6};  // 1/m at the peak
  double ozone_center_altitude_m = 25e3;  // m, altitude of the tent's peak
  double ozone_width_m = 30e3;            // m, full width of the tent (density > 0 over this span)

  // Sun: top-of-atmosphere illuminance at normal incidence, per channel (white sun). Must
  // equal the preset's sun_illuminance_lux so the sky and the sun disc stay consistent.
  double sun_illuminance_lux = 128000.0;  // lux

  // Quadrature.
  int view_steps = 64;       // segments along each view ray (plus up to 2 at the planet-shadow boundary)
  int sun_steps = 32;        // segments along each ray toward the sun (optical depth, numeric)
  int azimuth_samples = 16;  // relative sun azimuths averaged per LUT node (midpoints over [0, pi])

  // Returns false and explains in *why (option name, value, expectation) unless every field
  // is finite and within its physical bounds:
  //   planet_radius_m [1e3, 1e8]; atmosphere thickness (top - radius) (0, 1e6] m;
  //   scale heights and ozone width [1, 1e6] m; ozone centre within the atmosphere;
  //   sun_illuminance_lux (0, 2e5] (the preset's bounds);
  //   coefficients >= 0 with a vertical optical depth (coefficient x scale height, or x ozone
  //   width) <= 50 per term: beyond it single scattering leaves every LUT at zero.
  bool IsValid(std::string* why) const;
};

// Fills `luts` (grid given by luts.grid; every table must already have the size
// SkyLuts::Resize gives it) with single-scattering LUTs. Throws skycal::Error on invalid
// options or malformed tables.
//
// For the node (row, col): sun zenith ts with cos(ts) = 1 - row / (n_theta - 1) * (1 - cos ts_max),
// view elevation e with sin(e) = (col / (n_gamma - 1))^2 (the mapping of sky_model.glsl.h).
//   rayleigh[c] = E_sun * beta_R[c] * < integral_0^L rho_R(h(s)) T_c(o -> x(s)) T_c(x(s) -> sun) ds >
//   mie[c]      = E_sun * beta_M    * < same with rho_M >
// where x(s) = observer + s * view, L the distance to the top of the atmosphere, T the
// transmittance (Rayleigh + Mie extinction + ozone absorption), T(x -> sun) = 0 where the
// planet blocks the sun (the planet's shadow), and < > the mean over relative sun azimuth.
// The phase function is constant along a ray toward a distant sun, so it factors out of
// the integral exactly; only T(x -> sun) depends on the azimuth, which a 2D LUT cannot
// hold. The mean over azimuth is the least-squares constant for the phase-free integral
// (it minimises the integral over azimuth of (I(phi) - LUT)^2), and does not depend on the
// haziness g, which the preset sets independently of the bake.
// isotropic: multiple scattering is not estimated; the table is filled with zeros.
// sun_transmittance[row] = T(observer -> sun), 0 when the sun is below the observer's
// geometric horizon (blocked by the planet).
// Single scattering is exactly zero once the planet's shadow covers every lit point of the
// atmosphere seen by the observer (sun more than ~16 deg below the horizon for a 60 km
// atmosphere): deep-twilight rows come out zero.
void BakeSingleScattering(const AtmosphereOptions& opts, SkyLuts& luts);

}  // namespace skycal::render
