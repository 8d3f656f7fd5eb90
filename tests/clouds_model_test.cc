// The cloud model's analytic checks (clouds/model/*.glsl.h through the double instance):
// Beer transmittance of a uniform slab and of a shaped layer within the march's step-error
// bound, Henyey-Greenstein normalisation, energy conservation of single scattering,
// Beer-Powder values, coverage 0 -> the clear sky exactly, and the parameter section.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <nlohmann/json.hpp>

#include "cloud_test_scenes.h"
#include "resolved_clouds.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/composite.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"

namespace skycal::clouds {
namespace {
constexpr double kPi = std::numbers::pi;

render::Preset DefaultPreset() { return render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json"); }

struct Fixture {
  render::Preset preset = DefaultPreset();
  CloudParams params;
  CloudNoise noise = testing::ConstantCloudNoise(1.0f, 1.0f);
  WeatherMap weather = testing::UniformWeather(1.0f, 0.0f, 0.5f);
  CloudRenderRequest request;
  CloudScene scene() const { return {&preset, &params, &noise, &weather}; }
  CloudShadeD shade() const { return ResolveCloudShade(scene(), request); }
};

glsl::Vec3<double> Dir(double elevation_deg, double azimuth_deg) {
  const double e = elevation_deg * kPi / 180.0, a = azimuth_deg * kPi / 180.0;
  return {std::sin(a) * std::cos(e), std::sin(e), std::cos(a) * std::cos(e)};
}

// Path length inside the shell [R + b, R + t] from a camera at height h below it, along a
// ray of elevation e: independent of the model's stable-root code.
double ShellPath(double R, double h, double b, double t, double e) {
  auto far = [&](double a) {
    const double rc = R + h, mu = std::sin(e);
    return -rc * mu + std::sqrt(rc * rc * mu * mu - rc * rc + (R + a) * (R + a));
  };
  return far(t) - far(b);
}

// Beer's law through a uniform slab: base noise 1, coverage 1, shaping 0 -> density 1, so
// sigma_t = extinction everywhere in the layer. The march samples the midpoint of n equal
// steps spanning exactly [t0, t1] (ray-sphere roots): for a constant integrand the midpoint
// rule is exact, so the optical depth's only error is rounding, n steps x 1 ulp relative
// (n <= 128: < 1e-13 in double). Bound used: |T - exp(-sigma L)| <= 1e-12. Both the naive
// march and the game's (the cheap march finds cloud at its first sample and steps back to
// t0, so the full steps again span [t0, t1]; opacity stays above the stop threshold).
TEST(CloudsModel, UniformSlabBeerTransmittance) {
  for (bool game : {false, true}) {
    Fixture f;
    f.params.height_shaping = 0.0;
    f.params.horizon_rule = 0.0;
    // Optical depth 0.75 at the zenith, 5.4 at 8 deg: T stays above the opacity stop (1e-3).
    f.params.extinction_per_m = 0.0003;
    f.request.march = game ? MarchOptions{} : MarchOptions::Naive();
    const CloudShadeD s = f.shade();
    CpuCloudTextures tex(f.noise, f.weather);
    CloudModelD m(tex);
    for (double elevation : {90.0, 45.0, 20.0, 8.0}) {
      const auto r = m.cloud_march(Dir(elevation, 30.0), s);
      const double L = std::min(ShellPath(s.planet_radius, s.camera_height, s.layer_bottom, s.layer_top, elevation * kPi / 180.0),
                                s.draw_distance - ShellPath(s.planet_radius, s.camera_height, 0.0, s.layer_bottom, elevation * kPi / 180.0));
      const double expected = std::exp(-s.extinction * L);
      EXPECT_NEAR(r.transmittance, expected, 1e-12) << "elevation " << elevation << " game " << game;
    }
  }
}

// A shaped layer (cumulus gradient x bottom ramp, base noise 1, coverage 1) looking
// straight up, where altitude = camera height + t. Midpoint rule error over [t0, t1] with
// n steps of size dt: |tau_n - tau| <= sigma (L dt^2 / 24) max|f''(t)|, f the density
// profile (composite midpoint rule). max|f''| is measured on a fine grid of the model's own
// profile (central differences, 100x finer than dt) and taken x1.5 for safety; the
// reference optical depth is the same profile integrated with 65,536 midpoint steps.
TEST(CloudsModel, ShapedLayerWithinMidpointBound) {
  Fixture f;
  f.params.horizon_rule = 0.0;
  f.params.extinction_per_m = 0.004;
  f.request.march = MarchOptions::Naive();
  const CloudShadeD s = f.shade();
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  auto density = [&](double altitude) {
    const auto w = m.cloud_weather(0.0, 0.0, altitude, s);
    const double base = m.cloud_base_density(0.0, 0.0, altitude, w, s);
    return base > 0.0 ? m.cloud_full_density(base, 0.0, 0.0, altitude, s) : 0.0;
  };
  const double L = s.layer_top - s.layer_bottom;
  const int n = s.steps_zenith;
  const double dt = L / n;
  double tau = 0.0;
  const int fine = 65536;
  for (int i = 0; i < fine; ++i) tau += density(s.layer_bottom + (i + 0.5) * L / fine) * (L / fine);
  tau *= s.extinction;
  double f2 = 0.0;
  const double hstep = dt / 100.0;
  for (double a = s.layer_bottom + hstep; a < s.layer_top - hstep; a += hstep) {
    f2 = std::max(f2, std::abs(density(a + hstep) - 2.0 * density(a) + density(a - hstep)) / (hstep * hstep));
  }
  const double bound = 1.5 * s.extinction * L * dt * dt / 24.0 * f2;
  const auto r = m.cloud_march(Dir(90.0, 0.0), s);
  const double tau_march = -std::log(r.transmittance);
  EXPECT_LE(std::abs(tau_march - tau), bound) << "tau " << tau << " bound " << bound;
  EXPECT_GT(tau, 1.0);  // a meaningful depth, not a vacuous check
}

// The 2D cirrus sheet over a base noise of 1 (pattern 1 x coverage remap = 1 at coverage
// 1): straight up its transmittance is exp(-depth) exactly (mu = 1), and at 30 deg the slant
// through the spherical sheet, exp(-depth / mu), mu from the sphere's geometry.
TEST(CloudsModel, CirrusSheetTransmittance) {
  Fixture f;
  f.params.coverage_scale = 0.0;  // the volumetric layer empty
  f.params.cirrus_coverage = 1.0;
  f.params.cirrus_optical_depth = 0.4;
  const CloudShadeD s = f.shade();
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  EXPECT_NEAR(m.cloud_march(Dir(90.0, 0.0), s).transmittance, std::exp(-0.4), 1e-12);
  const double e = 30.0 * kPi / 180.0, rc = s.planet_radius + s.camera_height, rs = s.planet_radius + s.cirrus_altitude;
  const double mu = std::sqrt(1.0 - std::pow(rc * std::cos(e) / rs, 2.0));  // sin rule at the sheet
  EXPECT_NEAR(m.cloud_march(Dir(30.0, 0.0), s).transmittance, std::exp(-0.4 / mu), 1e-9);
  EXPECT_DOUBLE_EQ(m.cloud_march(Dir(-5.0, 0.0), s).transmittance, 1.0);  // below the horizon: ground
}

// The lag (grid steps) at which a periodic n x n field's autocorrelation along x (or z)
// first falls below 1/2: its features' length along that axis.
double HalfCorrelationLag(const std::vector<double>& f, int n, bool along_x) {
  double mean = 0.0;
  for (double v : f) mean += v / f.size();
  auto corr = [&](int lag) {
    double c = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int i2 = along_x ? (i + lag) % n : i, j2 = along_x ? j : (j + lag) % n;
        c += (f[j * n + i] - mean) * (f[j2 * n + i2] - mean);
      }
    return c;
  };
  const double c0 = corr(0);
  for (int lag = 1; lag < n / 2; ++lag)
    if (corr(lag) < 0.5 * c0) return lag;
  return n / 2;
}

// The alto/cirrus sheet has the talk's "big arcing bands and little puffs" (Schneider
// 2015), not blobs: over one cirrus tile (30 km, 256 x 256 samples of 117 m) its pattern is
// long along the bands (x) and narrow across them (z). Asserted: the half-correlation
// length along x at least 3x that across (the bands are stretched 8x; the puffs shorten
// both), and the width across between 1/64 and 1/8 of the tile (0.5 to 3.75 km: bands a
// few km wide, puffs below that). Control: an isotropic slice of the base noise (R x its
// Worley fbm, unstretched) has a ratio near 1 and fails the first assertion.
TEST(CloudsModel, CirrusPatternIsBandsNotBlobs) {
  Fixture f;
  f.noise = LoadOrGenerateCloudNoise(1, (std::filesystem::temp_directory_path() / "skycal-clouds-parity-cache").string());
  f.params.cirrus_coverage = 1.0;
  const CloudShadeD s = f.shade();
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  constexpr int n = 256;
  std::vector<double> bands(n * n), blobs(n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = s.cirrus_tile * i / n, z = s.cirrus_tile * j / n;
      bands[j * n + i] = m.cirrus_pattern(x, z, s);
      const double k = CloudModelD::CLOUD_BASE_SIZE / s.cirrus_tile;
      const auto t = m.sample_base_noise(x * k, 0.5, z * k);
      blobs[j * n + i] = t.r * t.fbm;
    }
  const double along = HalfCorrelationLag(bands, n, true), across = HalfCorrelationLag(bands, n, false);
  const double old_along = HalfCorrelationLag(blobs, n, true), old_across = HalfCorrelationLag(blobs, n, false);
  std::printf("cirrus half-correlation lags (117 m steps): bands along %.0f across %.0f; old slice %.0f / %.0f\n", along,
              across, old_along, old_across);
  EXPECT_GE(along, 3.0 * across);
  EXPECT_GE(across, n / 64.0);
  EXPECT_LE(across, n / 8.0);
  EXPECT_LT(old_along, 3.0 * old_across);  // control: the metric tells blobs from bands
}

// HZD's horizon rule is a distance from the player: beyond horizon_start (15 km) the
// coverage tends to horizon_coverage, complete at horizon_end (35 km). The model applies it
// by each sample's distance along the view ray, not by the pixel's elevation: an empty map
// (coverage 0) with horizon_coverage 1, a slab (base noise 1, no erosion), so the density
// along a ray is smooth_ramp(15 km, 35 km, t) exactly and the optical depth is
// extinction x its integral over the ray's part in the layer. A ray at 8 deg enters the
// layer at ~10.7 km and leaves at ~27.5 km: cut at 15 km it is clear (T = 1 exactly: a
// per-elevation rule would shade the whole pixel alike); to 35 km its depth matches the
// integral. Bound: the composite midpoint rule's extinction x L dt^2 / 24 x max|f''|, f'' <=
// 6 / (20 km)^2 (a smoothstep; C1 at 15 km, so the rule keeps its order): 4.2e-5 in depth
// here (measured 1.2e-5).
TEST(CloudsModel, HorizonRuleFollowsTheDistanceAlongTheRay) {
  Fixture f;
  f.weather = testing::UniformWeather(0.0f, 0.0f, 0.5f);
  f.params.height_shaping = 0.0;
  f.params.erosion = 0.0;
  f.params.horizon_rule = 1.0;
  f.params.horizon_coverage = 1.0;
  f.params.extinction_per_m = 0.0002;
  f.request.march = MarchOptions::Naive();
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  const double e = 8.0;
  f.params.draw_distance_m = 15000.0;
  EXPECT_EQ(m.cloud_march(Dir(e, 30.0), f.shade()).transmittance, 1.0);
  f.params.draw_distance_m = 35000.0;
  const CloudShadeD s = f.shade();
  const double er = e * kPi / 180.0;
  const double rc = s.planet_radius + s.camera_height, mu = std::sin(er);
  auto far = [&](double a) { return -rc * mu + std::sqrt(rc * rc * mu * mu - rc * rc + (s.planet_radius + a) * (s.planet_radius + a)); };
  const double t0 = far(s.layer_bottom), t1 = std::min(far(s.layer_top), s.draw_distance);
  ASSERT_LT(t0, 15000.0);
  ASSERT_GT(t1, 25000.0);
  double integral = 0.0;
  const int fine = 200000;
  for (int i = 0; i < fine; ++i) {
    const double t = t0 + (i + 0.5) * (t1 - t0) / fine;
    const double x = std::clamp((t - 15000.0) / 20000.0, 0.0, 1.0);
    integral += x * x * (3.0 - 2.0 * x) * (t1 - t0) / fine;
  }
  const double tau = -std::log(m.cloud_march(Dir(e, 30.0), s).transmittance);
  const int n = static_cast<int>(std::floor(s.steps_horizon + (s.steps_zenith - s.steps_horizon) * mu + 0.5));
  const double dt = (t1 - t0) / n;
  const double bound = s.extinction * (t1 - t0) * dt * dt / 24.0 * 6.0 / (20000.0 * 20000.0);
  EXPECT_NEAR(tau, s.extinction * integral, bound);
  EXPECT_GT(tau, 0.5);  // a meaningful depth
  // Control: the rule off, the empty map stays clear at any distance.
  f.params.horizon_rule = 0.0;
  EXPECT_EQ(m.cloud_march(Dir(e, 30.0), f.shade()).transmittance, 1.0);
}

// The sun below the horizon: no direct term (the clouds are lit by the sky's ambient
// alone), every value finite, the radiance exactly that of the same march with the sun's
// illuminance zeroed by hand; above the horizon the direct term is there (control).
TEST(CloudsModel, SunBelowTheHorizonLightsByAmbientOnly) {
  Fixture f;
  f.noise = testing::SinusoidCloudNoise();
  f.weather = testing::PatchyWeather(0.6f, 0.5f);
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  for (double sun_elevation : {-0.5, -8.0}) {
    f.request.sun_dir = latlong::DirectionFromElevationAzimuthDeg(sun_elevation, 40.0);
    const CloudShadeD s = f.shade();
    EXPECT_EQ(s.sun_illuminance.x, 0.0);
    EXPECT_EQ(s.sun_illuminance.y, 0.0);
    EXPECT_EQ(s.sun_illuminance.z, 0.0);
    CloudShadeD ambient_only = s;
    ambient_only.sun_illuminance = glsl::Vec3<double>(0.0, 0.0, 0.0);
    bool some_cloud = false;
    for (double elevation : {60.0, 10.0}) {
      const auto r = m.cloud_march(Dir(elevation, 40.0), s);
      const auto a = m.cloud_march(Dir(elevation, 40.0), ambient_only);
      ASSERT_TRUE(std::isfinite(r.radiance.x) && std::isfinite(r.radiance.y) && std::isfinite(r.radiance.z) && std::isfinite(r.transmittance));
      EXPECT_EQ(r.radiance.x, a.radiance.x);
      EXPECT_EQ(r.radiance.z, a.radiance.z);
      EXPECT_GE(r.radiance.y, 0.0);
      some_cloud = some_cloud || r.transmittance < 0.9;
    }
    EXPECT_TRUE(some_cloud) << "sun " << sun_elevation;
  }
  f.request.sun_dir = latlong::DirectionFromElevationAzimuthDeg(2.0, 40.0);
  EXPECT_GT(f.shade().sun_illuminance.x, 0.0);
}

// The shared source wraps texel indices with a power-of-two mask: a weather map of another
// size reaching the renderer directly (not through LoadWeatherMap) is refused, named.
TEST(CloudsModel, WeatherMapOfANonPowerOfTwoSizeIsRefused) {
  Fixture f;
  f.weather.width = f.weather.height = 3;
  f.weather.rgb.assign(27, 0.5f);
  try {
    f.shade();
    FAIL() << "a 3x3 weather map was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("weather map is 3x3 texels (expected a power of two"), std::string::npos) << e.what();
  }
  f.weather = testing::UniformWeather(0.5f, 0.0f, 0.5f);  // control: 4x4 passes
  EXPECT_NO_THROW(f.shade());
}

// Each HG lobe and their blend integrate to 1 over the sphere: integral of p 2 pi dmu over
// mu in [-1, 1] by the midpoint rule in u = 1 - mu on two geometric grids, from u = 0 up
// and from u = 2 down (dense at the forward and the backward peak, whose width is
// ~(1 - |g|)^2). 2 x 20,000 cells from 1e-9: the midpoint error, h^2/24 |p''| per cell
// with h/u ~ 1e-3, is ~1e-7 relative; tolerance 1e-5.
TEST(CloudsModel, PhaseLobesIntegrateToOne) {
  Fixture f;
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  const int cells = 20000;
  const double u0 = 1e-9, ratio = std::pow(1.0 / u0, 1.0 / (cells - 1));
  auto integrate = [&](auto phase) {
    double sum = 0.0;
    for (int side = 0; side < 2; ++side) {
      double a = 0.0, b = u0;
      for (int i = 0; i < cells; ++i) {
        const double mid = 0.5 * (a + b);
        sum += phase(side == 0 ? mid : 2.0 - mid) * (b - a) * 2.0 * kPi;
        a = b;
        b = std::min(b * ratio, 1.0);
      }
    }
    return sum;
  };
  for (double g : {-0.9, -0.3, 0.0, 0.5, 0.8, 0.9, 0.99}) {
    EXPECT_NEAR(integrate([&](double u) { return m.phase_hg(u, g); }), 1.0, 1e-5) << "g " << g;
  }
  for (double blend : {0.0, 0.25, 0.7, 1.0}) {
    EXPECT_NEAR(integrate([&](double u) { return m.phase_two_lobe(u, 0.5, 0.95, blend); }), 1.0, 1e-5) << blend;
  }
}

// Beer-Powder 2 exp(-d) (1 - exp(-2d)): 0 at d = 0, its maximum 4 / (3 sqrt 3) at
// d = ln(3) / 2, 2 e^-1 (1 - e^-2) at 1; strength 0 leaves Beer's exp(-d).
TEST(CloudsModel, PowderValues) {
  Fixture f;
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  EXPECT_DOUBLE_EQ(m.beer_powder(0.0), 0.0);
  EXPECT_NEAR(m.beer_powder(0.5 * std::log(3.0)), 4.0 / (3.0 * std::sqrt(3.0)), 1e-15);
  EXPECT_NEAR(m.beer_powder(1.0), 2.0 * std::exp(-1.0) * (1.0 - std::exp(-2.0)), 1e-15);
  EXPECT_NEAR(m.beer_powder(1e-4), 4e-4, 1e-7);  // 4 d for small d: edges go dark
  CloudShadeD s = f.shade();
  s.powder_strength = 0.0;
  EXPECT_DOUBLE_EQ(m.sun_attenuation(0.7, 0.3, s), std::exp(-0.7));
  s.powder_strength = 1.0;
  s.powder_view_fade = 0.0;
  EXPECT_NEAR(m.sun_attenuation(0.7, 0.3, s), m.beer_powder(0.7), 1e-15);
  s.powder_view_fade = 1.0;  // toward the sun (1 - mu = 0): no powder
  EXPECT_NEAR(m.sun_attenuation(0.7, 0.0, s), std::exp(-0.7), 1e-15);
  // The march's per-ray form of the sun term (phases and powder weight taken once a ray,
  // exp(-2d) as exp(-d)^2) equals the direct sum to rounding, for every octave count.
  s.powder_strength = 0.4;
  s.powder_view_fade = 0.7;
  for (int octaves = 0; octaves <= 4; ++octaves) {
    s.ms_octaves = octaves;
    for (double one_minus_mu : {0.0, 0.3, 1.2, 2.0}) {
      for (double tau : {0.0, 0.05, 1.0, 7.0}) {
        const auto direct = m.sun_inscatter(tau, one_minus_mu, s);
        const auto hoisted = m.sun_inscatter_ray(tau, m.sun_ray(one_minus_mu, s), s);
        EXPECT_NEAR(hoisted.x, direct.x, 1e-13 * std::abs(direct.x) + 1e-300) << octaves << " " << one_minus_mu << " " << tau;
        EXPECT_NEAR(hoisted.z, direct.z, 1e-13 * std::abs(direct.z) + 1e-300);
      }
    }
  }
}

// Energy: albedo 1, no absorption (no rain), single scattering, no powder, ambient, ground
// or atmosphere blend: a camera inside a uniform slab sees L(w) <= E_sun p(w) (1 - T(w))
// per view (light reaching a sample is at most E_sun; the energy-conserving step scatters
// at most what it removes), so over the sphere integral of L dw <= E_sun: out-scattered <= incident.
TEST(CloudsModel, SingleScatteringConservesEnergy) {
  Fixture f;
  f.params.height_shaping = 0.0;
  f.params.horizon_rule = 0.0;
  f.params.scattering_albedo = 1.0;
  f.params.camera_height_m = 2750.0;  // mid-layer: cloud in every direction
  f.params.extinction_per_m = 0.002;
  f.params.ms_octaves = 0.0;
  f.params.powder_strength = 0.0;
  f.request.sun_dir = {0.3, 0.8, 0.2};
  f.request.march = MarchOptions::Naive();
  CloudShadeD s = f.shade();
  s.sky_irradiance_up = s.ground_radiance = glsl::Vec3<double>(0.0);
  s.atmosphere_blend = 1e30;
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModelD m(tex);
  const int w = 96, h = 48;
  double integral = 0.0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto d = latlong::PixelDirection(x, y, w, h);
      const glsl::Vec3<double> v(d[0], d[1], d[2]);
      const auto r = m.cloud_march(v, s);
      const glsl::Vec3<double> diff = v - s.sun_dir;
      const double bound = s.sun_illuminance.y * m.phase_two_lobe(0.5 * glsl::dot(diff, diff), s.g1, s.g2, s.phase_blend) *
                           (1.0 - r.transmittance);
      ASSERT_LE(r.radiance.y, bound * (1.0 + 1e-12)) << x << "," << y;
      integral += r.radiance.y * latlong::PixelSolidAngle(x, y, w, h);
    }
  }
  EXPECT_LE(integral, s.sun_illuminance.y);
  EXPECT_GT(integral, 0.05 * s.sun_illuminance.y);  // and the test scatters a real amount
}

// Coverage 0 (scale 0, or an empty weather map without rain or horizon rule) -> T = 1 and
// L_cloud = 0 in every pixel, so the composite equals the clear sky bit for bit.
TEST(CloudsModel, CoverageZeroCompositesToTheClearSky) {
  for (int variant = 0; variant < 2; ++variant) {
    Fixture f;
    f.noise = testing::SinusoidCloudNoise();
    if (variant == 0) {
      f.params.coverage_scale = 0.0;
      f.weather = testing::PatchyWeather(0.6f, 0.5f);
    } else {
      f.weather = testing::UniformWeather(0.0f, 0.0f, 1.0f);
      f.params.horizon_rule = 0.0;
    }
    for (double elevation : {-10.0, 20.0, 90.0}) {
      f.request.width = 64;
      f.request.height = 32;
      f.request.sun_dir = {0.0, std::sin(elevation * kPi / 180.0), std::cos(elevation * kPi / 180.0)};
      render::RenderRequest sky_request;
      sky_request.sun_dir = f.request.sun_dir;
      sky_request.width = 64;
      sky_request.height = 32;
      const ImageRGB sky = render::CreateRenderer(render::Backend::kCpu)->Render(f.preset, sky_request);
      for (CloudPrecision p : {CloudPrecision::kDouble, CloudPrecision::kFloat}) {
        const CloudImage clouds = CreateCpuCloudRenderer(p, 2)->Render(f.scene(), f.request);
        const ImageRGB out = CompositeClouds(sky, clouds);
        EXPECT_EQ(out.pixels, sky.pixels) << "variant " << variant << " elevation " << elevation;
      }
    }
  }
}

// --cloud-cheap-light-opacity (MarchOptions::cheap_light_opacity; the added error: docs/benchmarks.md):
// the threshold picks which lit samples take base-shape-only light samples and nothing else.
// Identities: at 1 no sample passes it (opacity 1 - T > 1 never holds), so the image equals
// the one without cheap light samples bit for bit; between 0.3 and 0.6 the transmittance is
// the same bit for bit (light samples never change the primary march), pixels whose
// opacity stays <= 0.3 are unchanged, and some cloudy pixel changes (the control: the
// shortcut is taken at all in this scene).
TEST(CloudsModel, CheapLightOpacityChangesOnlyTheLightPastIt) {
  Fixture f;
  f.noise = testing::SinusoidCloudNoise();
  f.weather = testing::PatchyWeather(0.6f, 0.5f);
  f.request.width = 64;
  f.request.height = 32;
  f.request.sun_dir = {0.0, std::sin(25.0 * kPi / 180.0), std::cos(25.0 * kPi / 180.0)};
  auto render = [&](bool cheap, double opacity) {
    f.request.march = MarchOptions{};
    f.request.march.cheap_light = cheap;
    f.request.march.cheap_light_opacity = opacity;
    return CreateCpuCloudRenderer(CloudPrecision::kFloat, 2)->Render(f.scene(), f.request);
  };
  const CloudImage off = render(false, 0.3), at1 = render(true, 1.0), hzd = render(true, 0.3), at06 = render(true, 0.6);
  EXPECT_EQ(at1.radiance.pixels, off.radiance.pixels);
  EXPECT_EQ(at1.transmittance, off.transmittance);
  EXPECT_EQ(at06.transmittance, hzd.transmittance);
  int changed = 0, thin = 0;
  for (size_t i = 0; i < hzd.transmittance.size(); ++i) {
    bool differs = false;
    for (int c = 0; c < 3; ++c) differs = differs || hzd.radiance.pixels[3 * i + c] != at06.radiance.pixels[3 * i + c];
    if (hzd.transmittance[i] >= 0.7f) {
      ++thin;
      EXPECT_FALSE(differs) << "pixel " << i << " (T " << hzd.transmittance[i] << ")";
    }
    changed += differs;
  }
  EXPECT_GT(thin, 0);
  EXPECT_GT(changed, 0);
}

TEST(CloudsModel, CompositeIsSkyTimesTransmittancePlusClouds) {
  ImageRGB sky(2, 1);
  sky.pixels = {1, 2, 3, 4, 5, 6};
  CloudImage c;
  c.radiance = ImageRGB(2, 1);
  c.radiance.pixels = {0.5f, 0.5f, 0.5f, 1, 0, 0};
  c.transmittance = {0.5f, 0.0f};
  EXPECT_EQ(CompositeClouds(sky, c).pixels, (std::vector<float>{1.0f, 1.5f, 2.0f, 1, 0, 0}));
  c.transmittance = {1.0f};
  EXPECT_THROW(CompositeClouds(sky, c), Error);
}

// The lighting fit (docs/cloud-fitting.md) differentiates the model: the shared source instantiates on
// ceres::Jet, and its derivatives of a whole march with respect to lighting parameters
// match central finite differences of the double model (relative 1e-5: the step h = 1e-6
// relative leaves truncation ~h^2 and rounding ~1e-16/h ~ 1e-10).
TEST(CloudsModel, JetDerivativesOfTheMarchMatchFiniteDifferences) {
  using J = ceres::Jet<double, 3>;
  Fixture f;
  f.noise = testing::SinusoidCloudNoise();
  f.weather = testing::PatchyWeather(0.6f, 0.5f);
  f.request.sun_dir = {0.4, 0.5, 0.77};
  const CloudShadeD s = f.shade();
  CpuCloudTextures tex(f.noise, f.weather);
  CloudModel<J, CpuCloudTextures> mj(tex);
  CloudModelD md(tex);
  auto js = CastCloudShade<CloudModel<J, CpuCloudTextures>::CloudShadeParams>(s);
  js.g1 = J(s.g1, 0);
  js.powder_strength = J(s.powder_strength, 1);
  js.ambient_strength = J(s.ambient_strength, 2);
  int checked = 0;
  for (double elevation : {5.0, 20.0, 60.0}) {
    for (double azimuth : {0.0, 120.0, 250.0}) {
      const auto dir = Dir(elevation, azimuth);
      const auto r = mj.cloud_march(glsl::Vec3<J>(J(dir.x), J(dir.y), J(dir.z)), js);
      if (r.transmittance.a > 0.999) continue;  // no cloud on this ray
      double* fields[3] = {nullptr, nullptr, nullptr};
      CloudShadeD sp = s;
      fields[0] = &sp.g1;
      fields[1] = &sp.powder_strength;
      fields[2] = &sp.ambient_strength;
      for (int k = 0; k < 3; ++k) {
        const double h = 1e-6 * std::max(std::abs(*fields[k]), 1.0), v = *fields[k];
        *fields[k] = v + h;
        const double up = md.cloud_march(dir, sp).radiance.y;
        *fields[k] = v - h;
        const double down = md.cloud_march(dir, sp).radiance.y;
        *fields[k] = v;
        const double fd = (up - down) / (2.0 * h);
        EXPECT_NEAR(r.radiance.y.v[k], fd, 1e-5 * std::abs(r.radiance.y.a) + 1e-9) << elevation << " " << azimuth << " " << k;
      }
      ++checked;
    }
  }
  EXPECT_GE(checked, 3);
}

// render::Preset carries the section opaquely: LoadPreset -> SavePreset -> LoadPreset keeps
// it unchanged, and the preset's files include the weather map it names (file safety).
TEST(CloudsParams, PresetCarriesTheSectionThroughAndListsTheWeatherMap) {
  const std::string bundled = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_cloudy.json";
  const render::Preset p = render::LoadPreset(bundled);
  ASSERT_FALSE(p.clouds_json.empty());
  const CloudParams c = ParseCloudSectionText(p.clouds_json, bundled);
  EXPECT_EQ(c.weather_map, "default_cloudy.weather.exr");
  const auto files = render::PresetFiles(bundled);
  EXPECT_NE(std::find(files.begin(), files.end(),
                      std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_cloudy.weather.exr"),
            files.end());
  const std::string dir = (std::filesystem::temp_directory_path() / ("skycal-clouds-preset-" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  render::SavePreset(p, dir + "/copy.json");
  EXPECT_EQ(render::LoadPreset(dir + "/copy.json").clouds_json, p.clouds_json);
  std::filesystem::remove_all(dir);
}

TEST(CloudsParams, SectionRoundTripsAndRefusesBadFields) {
  CloudParams p;
  p.coverage_scale = 0.7;
  p.integration = 1.0;
  p.weather_map = "w.exr";
  const nlohmann::json j = CloudSectionToJson(p);
  const CloudParams q = ParseCloudSection(j, "t.json");
  EXPECT_EQ(q.coverage_scale, 0.7);
  EXPECT_EQ(q.integration_mode(), CloudIntegration::kHzdSimple);
  EXPECT_EQ(q.weather_map, "w.exr");
  EXPECT_EQ(CloudSectionToJson(q), j);
  auto error = [](const nlohmann::json& section) {
    try {
      ParseCloudSection(section, "t.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error({{"extintion", 0.1}}).find("did you mean 'extinction'"), std::string::npos);
  EXPECT_NE(error({{"layer_bottom", 5000.0}}).find("clouds.layer_bottom"), std::string::npos);
  EXPECT_NE(error({{"layer_bottom", -1.0}}).find("m)"), std::string::npos);
  EXPECT_NE(error({{"ms_octaves", 1.5}}).find("an integer"), std::string::npos);
  EXPECT_NE(error({{"integration", "fast"}}).find("energy-conserving"), std::string::npos);
  EXPECT_NE(error({{"horizon_rule", 1}}).find("true or false"), std::string::npos);
  MarchOptions m;
  std::string why;
  EXPECT_TRUE(m.IsValid(&why));
  m.steps_zenith = 0;
  EXPECT_FALSE(m.IsValid(&why));
  EXPECT_NE(why.find("steps_zenith"), std::string::npos);
  m.steps_zenith = 1000000;
  EXPECT_FALSE(m.IsValid(&why));
}

}  // namespace
}  // namespace skycal::clouds
