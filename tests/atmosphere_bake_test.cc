// The single-scattering LUT baker (render/src/atmosphere_bake.cc): analytic limits,
// an independent brute-force ray march, and the plausibility of the sky the model shows
// with the baked tables.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "skycal/core/error.h"
#include "skycal/render/atmosphere_bake.h"
#include "skycal/render/preset.h"
#include "skycal/render/sky_model.h"

namespace skycal {
namespace {

using render::AtmosphereOptions;
using render::LutGrid;
using render::SkyLuts;
constexpr double kPi = std::numbers::pi;

SkyLuts Bake(const AtmosphereOptions& opts, const LutGrid& grid = LutGrid{}) {
  SkyLuts luts;
  luts.Resize(grid);
  render::BakeSingleScattering(opts, luts);
  return luts;
}

size_t Index(const SkyLuts& l, int row, int col, int ch) {
  return (static_cast<size_t>(row) * l.grid.n_gamma + col) * 3 + ch;
}

double Rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

// ---------------------------------------------------------------------------------------
// Model evaluation with the baked LUTs (the shared GLSL/C++ source, in double).
struct TestLutSource {
  const SkyLuts* luts;
  template <typename S>
  glsl::Vec3<S> texel(int lut, int row, int col) const {
    const std::vector<float>& t = lut == 0 ? luts->rayleigh : (lut == 1 ? luts->mie : luts->isotropic);
    const size_t i = Index(*luts, row, col, 0);
    return glsl::Vec3<S>(S(t[i]), S(t[i + 1]), S(t[i + 2]));
  }
};
using Model = model::SkyModel<double, TestLutSource>;
using Vec = glsl::Vec3<double>;

Model::SkyParams Params(const SkyLuts& luts, double sun_elevation_deg, double g) {
  Model::SkyParams p{};
  const double e = sun_elevation_deg * kPi / 180.0;
  p.sun_dir = Vec(std::cos(e), std::sin(e), 0.0);
  p.haziness_g = g;
  p.isotropic_weight = 0.0;
  p.overcast_weight = 0.0;
  p.overcast_zenith = 0.0;
  p.sun_radius = 0.2666 * kPi / 180.0;
  p.sun_one_minus_cos_radius = 2.0 * std::sin(0.5 * p.sun_radius) * std::sin(0.5 * p.sun_radius);
  p.sun_limb_u = 0.6;
  p.sun_centre_radiance = Vec(0.0);
  p.ground_radiance = Vec(0.0);
  p.lut_one_minus_cos_theta_max = 1.0 - std::cos(luts.grid.theta_max_deg * kPi / 180.0);
  p.lut_n_theta = luts.grid.n_theta;
  p.lut_n_gamma = luts.grid.n_gamma;
  return p;
}

// Rec.709 luminance of scene-linear RGB, cd/m^2.
double Luminance(const Vec& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; }

// View at elevation `el_deg` and azimuth `az_deg` from the sun's azimuth (the sun is in +X).
Vec View(double el_deg, double az_deg) {
  const double e = el_deg * kPi / 180.0, a = az_deg * kPi / 180.0;
  return Vec(std::cos(e) * std::cos(a), std::sin(e), std::cos(e) * std::sin(a));
}

struct SkySample {
  Vec zenith, horizon_side;  // horizon 90 deg in azimuth from the sun
};

SkySample Sample(const SkyLuts& luts, double sun_elevation_deg, double g = 0.8) {
  const auto p = Params(luts, sun_elevation_deg, g);
  TestLutSource src{&luts};
  Model m(src);
  return {m.sky_radiance(View(90.0, 0.0), p), m.sky_radiance(View(0.0, 90.0), p)};
}

// ---------------------------------------------------------------------------------------
// Independent brute force: midpoint rule with uniform steps in Cartesian coordinates.
struct Brute {
  AtmosphereOptions o;

  std::array<double, 3> Extinction(const std::array<double, 3>& x) const {
    const double h = std::max(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - o.planet_radius_m, 0.0);
    const double rr = std::exp(-h / o.rayleigh_scale_height_m), rm = std::exp(-h / o.mie_scale_height_m);
    const double oz = std::max(0.0, 1.0 - std::abs(h - o.ozone_center_altitude_m) / (0.5 * o.ozone_width_m));
    std::array<double, 3> k{};
    for (int c = 0; c < 3; ++c) {
      k[c] = o.rayleigh_scattering_per_m[c] * rr + o.mie_extinction_per_m * rm + o.ozone_absorption_per_m[c] * oz;
    }
    return k;
  }
  static double Dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  }
  double DistanceToTop(const std::array<double, 3>& x, const std::array<double, 3>& d) const {
    const double b = Dot(x, d), c = Dot(x, x) - o.atmosphere_top_m * o.atmosphere_top_m;
    return -b + std::sqrt(std::max(b * b - c, 0.0));
  }
  bool Blocked(const std::array<double, 3>& x, const std::array<double, 3>& d) const {
    const double b = Dot(x, d);
    return b < 0.0 && Dot(x, x) - b * b < o.planet_radius_m * o.planet_radius_m;
  }
  std::array<double, 3> Transmittance(const std::array<double, 3>& x, const std::array<double, 3>& d, int steps) const {
    if (Blocked(x, d)) return {0.0, 0.0, 0.0};
    const double len = DistanceToTop(x, d), ds = len / steps;
    std::array<double, 3> tau{};
    for (int i = 0; i < steps; ++i) {
      const double t = (i + 0.5) * ds;
      const auto k = Extinction({x[0] + t * d[0], x[1] + t * d[1], x[2] + t * d[2]});
      for (int c = 0; c < 3; ++c) tau[c] += k[c] * ds;
    }
    return {std::exp(-tau[0]), std::exp(-tau[1]), std::exp(-tau[2])};
  }
  // Rayleigh LUT entry (per channel) for sun zenith ts, view elevation e, averaged over the
  // same azimuth midpoints the baker uses.
  std::array<double, 3> RayleighLut(double cos_ts, double sin_e, int azimuths, int view_steps, int sun_steps) const {
    const double r0 = o.planet_radius_m + o.observer_altitude_m;
    const std::array<double, 3> obs = {0.0, r0, 0.0};
    const double cos_e = std::sqrt(1.0 - sin_e * sin_e), sin_ts = std::sqrt(1.0 - cos_ts * cos_ts);
    const std::array<double, 3> v = {cos_e, sin_e, 0.0};
    const double len = DistanceToTop(obs, v), ds = len / view_steps;
    std::array<double, 3> sum{};
    for (int k = 0; k < azimuths; ++k) {
      const double phi = (k + 0.5) * kPi / azimuths;
      const std::array<double, 3> s = {sin_ts * std::cos(phi), cos_ts, sin_ts * std::sin(phi)};
      std::array<double, 3> tau_obs{};
      for (int i = 0; i < view_steps; ++i) {
        // Optical depth to the observer accumulated to the midpoint of segment i.
        const double t = (i + 0.5) * ds;
        const std::array<double, 3> x = {obs[0] + t * v[0], obs[1] + t * v[1], obs[2] + t * v[2]};
        const auto kx = Extinction(x);
        std::array<double, 3> tau_mid{};
        for (int c = 0; c < 3; ++c) tau_mid[c] = tau_obs[c] + 0.5 * kx[c] * ds;
        const auto ts = Transmittance(x, s, sun_steps);
        const double rho = std::exp(-std::max(std::sqrt(Dot(x, x)) - o.planet_radius_m, 0.0) / o.rayleigh_scale_height_m);
        for (int c = 0; c < 3; ++c) {
          sum[c] += rho * std::exp(-tau_mid[c]) * ts[c] * ds;
          tau_obs[c] += kx[c] * ds;
        }
      }
    }
    std::array<double, 3> lut{};
    for (int c = 0; c < 3; ++c) lut[c] = o.sun_illuminance_lux * o.rayleigh_scattering_per_m[c] * sum[c] / azimuths;
    return lut;
  }
};

// ---------------------------------------------------------------------------------------
// (a) Optically thin limit: with T ~ 1 the zenith entry for the sun at the zenith is the
// vertical column, E * beta * H * (1 - exp(-thickness / H)) for an observer at the ground.
// Required: within 1%; the exponential-segment quadrature is exact for vertical rays, so
// the remaining difference is the transmittance (1 - T ~ 1e-5) and float storage.
TEST(AtmosphereBake, OpticallyThinZenithMatchesAnalyticColumn) {
  AtmosphereOptions o;
  o.observer_altitude_m = 0.0;
  o.rayleigh_scattering_per_m = {1e-10, 2e-10, 4e-10};
  o.mie_scattering_per_m = 1e-10;
  o.mie_extinction_per_m = 1e-10;
  o.ozone_absorption_per_m = {0.0, 0.0, 0.0};
  const SkyLuts luts = Bake(o);
  const double thickness = o.atmosphere_top_m - o.planet_radius_m;
  const int zenith_col = luts.grid.n_gamma - 1;
  for (int c = 0; c < 3; ++c) {
    const double h = o.rayleigh_scale_height_m;
    const double expected = o.sun_illuminance_lux * o.rayleigh_scattering_per_m[c] * h * (1.0 - std::exp(-thickness / h));
    const double got = luts.rayleigh[Index(luts, 0, zenith_col, c)];
    EXPECT_LT(Rel(got, expected), 1e-4) << "channel " << c << ": " << got << " vs " << expected;
  }
  const double hm = o.mie_scale_height_m;
  const double expected_mie = o.sun_illuminance_lux * o.mie_scattering_per_m * hm * (1.0 - std::exp(-thickness / hm));
  EXPECT_LT(Rel(luts.mie[Index(luts, 0, zenith_col, 0)], expected_mie), 1e-4);
}

// (a') A slanted, optically thick node against an independent brute-force march (uniform
// midpoint steps, Cartesian geometry): sun zenith ~74 deg (row 20), view elevation ~3.8 deg
// (col 8). Checks the geometry of rows, columns and azimuths, not only the vertical case.
TEST(AtmosphereBake, SlantedNodeMatchesBruteForceMarch) {
  AtmosphereOptions o;
  o.azimuth_samples = 4;
  const SkyLuts luts = Bake(o);
  const LutGrid& g = luts.grid;
  const int row = 20, col = 8;
  const double cos_ts = std::cos(render::LutRowSunZenithRad(g, row));
  const double sin_e = std::sin(render::LutColumnElevationRad(g, col));
  const auto ref = Brute{o}.RayleighLut(cos_ts, sin_e, o.azimuth_samples, 3000, 600);
  for (int c = 0; c < 3; ++c) {
    EXPECT_LT(Rel(luts.rayleigh[Index(luts, row, col, c)], ref[c]), 3e-3)
        << "channel " << c << ": " << luts.rayleigh[Index(luts, row, col, c)] << " vs " << ref[c];
  }
}

// The same brute force in twilight (sun 5.2 deg below the horizon, row 30, horizon column):
// most of the view ray lies in the planet's shadow.
TEST(AtmosphereBake, TwilightNodeMatchesBruteForceMarch) {
  AtmosphereOptions o;
  o.azimuth_samples = 4;
  const SkyLuts luts = Bake(o);
  const LutGrid& g = luts.grid;
  const int row = 30, col = 0;
  const double cos_ts = std::cos(render::LutRowSunZenithRad(g, row));
  const auto ref = Brute{o}.RayleighLut(cos_ts, 0.0, o.azimuth_samples, 6000, 600);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(ref[c], 0.0);
    EXPECT_LT(Rel(luts.rayleigh[Index(luts, row, col, c)], ref[c]), 1e-2)
        << "channel " << c << ": " << luts.rayleigh[Index(luts, row, col, c)] << " vs " << ref[c];
  }
}

// (b) Direct sun at the zenith: exp(-tau) with tau from the exponential profiles and the
// ozone tent (column = half its width when the observer is below it and the top above).
// Required: within 0.5%; vertical rays are integrated exactly, so float storage dominates.
TEST(AtmosphereBake, ZenithSunTransmittanceMatchesAnalytic) {
  const AtmosphereOptions o;
  const SkyLuts luts = Bake(o);
  const double h0 = o.observer_altitude_m, top = o.atmosphere_top_m - o.planet_radius_m;
  auto column = [&](double H) { return H * (std::exp(-h0 / H) - std::exp(-top / H)); };
  const double ozone_column = 0.5 * o.ozone_width_m;
  ASSERT_LT(h0, o.ozone_center_altitude_m - 0.5 * o.ozone_width_m);
  ASSERT_GT(top, o.ozone_center_altitude_m + 0.5 * o.ozone_width_m);
  for (int c = 0; c < 3; ++c) {
    const double tau = o.rayleigh_scattering_per_m[c] * column(o.rayleigh_scale_height_m) +
                       o.mie_extinction_per_m * column(o.mie_scale_height_m) + o.ozone_absorption_per_m[c] * ozone_column;
    EXPECT_LT(Rel(luts.sun_transmittance[c], std::exp(-tau)), 1e-5)
        << "channel " << c << ": " << luts.sun_transmittance[c] << " vs " << std::exp(-tau);
  }
}

// Slanted sun rays against the brute-force march (rows 14 and 27: sun zenith ~61 and
// ~89 deg, the latter grazing the ground).
TEST(AtmosphereBake, SlantedSunTransmittanceMatchesBruteForce) {
  const AtmosphereOptions o;
  const SkyLuts luts = Bake(o);
  const Brute brute{o};
  for (int row : {14, 27}) {
    const double ts = render::LutRowSunZenithRad(luts.grid, row);
    const auto ref = brute.Transmittance({0.0, o.planet_radius_m + o.observer_altitude_m, 0.0},
                                         {std::sin(ts), std::cos(ts), 0.0}, 200000);
    for (int c = 0; c < 3; ++c) {
      EXPECT_LT(Rel(luts.sun_transmittance[row * 3 + c], ref[c]), 1e-4)
          << "row " << row << " channel " << c << ": " << luts.sun_transmittance[row * 3 + c] << " vs " << ref[c];
    }
  }
}

// (c) Plausibility of the default (Earth) bake through the model.
class DefaultBake : public ::testing::Test {
 protected:
  // (Its time is not asserted: speed lives in benchmarks, and a timed test fails on a
  // loaded machine.)
  static void SetUpTestSuite() { luts_ = new SkyLuts(Bake(AtmosphereOptions{})); }
  static void TearDownTestSuite() {
    delete luts_;
    luts_ = nullptr;
  }
  static SkyLuts* luts_;
};
SkyLuts* DefaultBake::luts_ = nullptr;

// Sun 60 deg high, g = 0.8. Clear-sky zenith luminance is typically 2000-8000 cd/m^2;
// single scattering alone gives less (~1300 cd/m^2 here: multiple scattering is missing).
TEST_F(DefaultBake, DaytimeZenithAndHorizon) {
  const SkySample s60 = Sample(*luts_, 60.0);
  const double y_zenith = Luminance(s60.zenith);
  EXPECT_GT(y_zenith, 1000.0);
  EXPECT_LT(y_zenith, 8000.0);
  // Blue sky at the zenith.
  EXPECT_GT(s60.zenith.z, s60.zenith.y);
  EXPECT_GT(s60.zenith.y, s60.zenith.x);
  // The horizon is brighter than the zenith for a high sun (longer path through the air).
  for (double el : {60.0, 45.0, 30.0}) {
    const SkySample s = Sample(*luts_, el);
    EXPECT_GT(Luminance(s.horizon_side), 2.0 * Luminance(s.zenith)) << "sun elevation " << el;
    EXPECT_GT(s.zenith.z, s.zenith.x) << "sun elevation " << el;
  }
  // The sky darkens as the sun sets.
  double prev = std::numeric_limits<double>::infinity();
  for (double el : {60.0, 30.0, 10.0, 2.0, 0.0, -3.0, -6.0}) {
    const double y = Luminance(Sample(*luts_, el).zenith);
    EXPECT_LT(y, prev) << "sun elevation " << el;
    prev = y;
  }
}

TEST_F(DefaultBake, SunTransmittanceReddensTowardTheHorizon) {
  const SkyLuts& l = *luts_;
  const double observer_dip_deg =
      std::acos(6360e3 / (6360e3 + AtmosphereOptions{}.observer_altitude_m)) * 180.0 / kPi;
  double prev_ratio = std::numeric_limits<double>::infinity();
  for (int row = 0; row < l.grid.n_theta; ++row) {
    const double zenith_deg = render::LutRowSunZenithRad(l.grid, row) * 180.0 / kPi;
    const float* t = &l.sun_transmittance[row * 3];
    if (zenith_deg > 90.0 + observer_dip_deg) {
      EXPECT_EQ(t[0], 0.0f) << "row " << row << ": the planet blocks the sun";
      EXPECT_EQ(t[1], 0.0f);
      EXPECT_EQ(t[2], 0.0f);
      continue;
    }
    EXPECT_GT(t[0], t[1]) << "row " << row;  // red passes best
    EXPECT_GT(t[1], t[2]) << "row " << row;
    if (row > 0) {
      for (int c = 0; c < 3; ++c) EXPECT_LT(t[c], l.sun_transmittance[(row - 1) * 3 + c]) << "row " << row;
    }
    const double blue_over_red = t[2] / t[0];
    EXPECT_LT(blue_over_red, prev_ratio) << "row " << row;
    prev_ratio = blue_over_red;
  }
  // Sun 2 deg above the horizon: strongly reddened.
  const auto t2 = render::SunTransmittance(l, 88.0 * kPi / 180.0);
  EXPECT_LT(t2[2] / t2[0], 0.1);
  // Overhead: about 0.94 / 0.87 / 0.77 (R, G, B) for this atmosphere.
  EXPECT_NEAR(l.sun_transmittance[0], 0.942, 0.01);
  EXPECT_NEAR(l.sun_transmittance[2], 0.768, 0.01);
}

// Single scattering in twilight: non-zero while some of the air the observer sees is still
// lit (the upper atmosphere toward the horizon), exactly zero once the planet's shadow
// covers all of it. For a 60 km atmosphere seen from the ground that happens at a sun
// depression of ~2 * acos(R / (R + 60 km)) = 15.8 deg, before the 18 deg of the last rows
// (real skies stay brighter: multiple scattering, which this baker does not estimate).
TEST_F(DefaultBake, TwilightRowsAreSmallButLitUntilTheShadowCoversTheAtmosphere) {
  const SkyLuts& l = *luts_;
  for (int row = 0; row < l.grid.n_theta; ++row) {
    const double depression_deg = render::LutRowSunZenithRad(l.grid, row) * 180.0 / kPi - 90.0;
    if (depression_deg <= 0.0) continue;
    for (int c = 0; c < 3; ++c) {
      // Horizon column, against the same channel with the sun overhead.
      const double r = l.rayleigh[Index(l, row, 0, c)], m = l.mie[Index(l, row, 0, c)];
      const double r_day = l.rayleigh[Index(l, 0, 0, c)], m_day = l.mie[Index(l, 0, 0, c)];
      if (depression_deg < 13.0) {
        EXPECT_GT(r, 0.0) << "row " << row << " channel " << c;
        EXPECT_GT(m, 0.0) << "row " << row << " channel " << c;
        EXPECT_LT(r, (depression_deg < 6.0 ? 0.2 : 1e-2) * r_day) << "row " << row << " channel " << c;
        EXPECT_LT(m, (depression_deg < 6.0 ? 0.2 : 1e-2) * m_day) << "row " << row << " channel " << c;
      } else if (depression_deg > 16.0) {
        for (int col = 0; col < l.grid.n_gamma; ++col) {
          EXPECT_EQ(l.rayleigh[Index(l, row, col, c)], 0.0f) << "row " << row << " col " << col;
          EXPECT_EQ(l.mie[Index(l, row, col, c)], 0.0f) << "row " << row << " col " << col;
        }
      }
    }
  }
  // Civil twilight through the model: small but visible.
  const SkySample s = Sample(l, -6.0);
  EXPECT_GT(Luminance(s.zenith), 0.0);
  EXPECT_LT(Luminance(s.zenith), 0.01 * Luminance(Sample(l, 30.0).zenith));
  EXPECT_GT(Luminance(s.horizon_side), Luminance(s.zenith));
}

// Every LUT column darkens (weakly) as the sun sinks: the integrand is T(o->x) T(x->sun)
// rho and T(x->sun) falls with the sun's height at every point. (Near the zenith the
// azimuth-averaged value is flat to ~1e-4, hence the tolerance.)
TEST_F(DefaultBake, LutsDarkenAsTheSunSinks) {
  const SkyLuts& l = *luts_;
  for (int row = 1; row < l.grid.n_theta; ++row) {
    for (int col = 0; col < l.grid.n_gamma; ++col) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_LE(l.rayleigh[Index(l, row, col, c)], l.rayleigh[Index(l, row - 1, col, c)] * (1.0 + 1e-3))
            << "row " << row << " col " << col;
        EXPECT_LE(l.mie[Index(l, row, col, c)], l.mie[Index(l, row - 1, col, c)] * (1.0 + 1e-3))
            << "row " << row << " col " << col;
      }
    }
  }
}

// (d) Non-negative and finite everywhere, for the default and for a stress case: a hazy,
// thick-aerosol atmosphere, an observer on the ground, a finer grid reaching the nadir sun.
void ExpectFiniteNonNegative(const SkyLuts& l, const std::string& what) {
  for (const auto* t : {&l.rayleigh, &l.mie, &l.isotropic, &l.sun_transmittance}) {
    for (size_t i = 0; i < t->size(); ++i) {
      ASSERT_TRUE(std::isfinite((*t)[i])) << what << " index " << i;
      ASSERT_GE((*t)[i], 0.0f) << what << " index " << i;
    }
  }
  for (float v : l.sun_transmittance) ASSERT_LE(v, 1.0f) << what;
  for (float v : l.isotropic) ASSERT_EQ(v, 0.0f) << what << ": multiple scattering is not estimated";
}

TEST_F(DefaultBake, FiniteNonNegativeAndAValidPreset) {
  ExpectFiniteNonNegative(*luts_, "default");
  render::Preset p;
  p.luts = *luts_;
  EXPECT_NO_THROW(render::ValidatePreset(p, "baked"));
}

TEST(AtmosphereBake, StressCaseFiniteNonNegative) {
  AtmosphereOptions o;
  o.observer_altitude_m = 0.0;
  o.mie_scattering_per_m = 100.0 * 3.996e-6;
  o.mie_extinction_per_m = 100.0 * 4.440e-6;
  o.view_steps = 16;
  o.sun_steps = 8;
  o.azimuth_samples = 3;
  const LutGrid grid{48, 40, 180.0};
  ExpectFiniteNonNegative(Bake(o, grid), "stress");
  o.observer_altitude_m = 59e3;  // near the top
  ExpectFiniteNonNegative(Bake(o, grid), "high observer");
}

// (e) Validation.
TEST(AtmosphereBake, IsValidRejectsBadOptions) {
  std::string why;
  EXPECT_TRUE(AtmosphereOptions{}.IsValid(&why)) << why;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* field;
    void (*edit)(AtmosphereOptions&, double);
    double value;
  };
  const Case cases[] = {
      {"rayleigh_scattering_per_m", [](AtmosphereOptions& o, double v) { o.rayleigh_scattering_per_m[1] = v; }, -1e-6},
      {"rayleigh_scattering_per_m", [](AtmosphereOptions& o, double v) { o.rayleigh_scattering_per_m[2] = v; }, nan},
      {"mie_scattering_per_m", [](AtmosphereOptions& o, double v) { o.mie_scattering_per_m = v; }, -1e-6},
      {"mie_scattering_per_m", [](AtmosphereOptions& o, double v) { o.mie_scattering_per_m = v; }, nan},
      {"mie_extinction_per_m", [](AtmosphereOptions& o, double v) { o.mie_extinction_per_m = v; }, 1e-6},  // < scattering
      {"mie_extinction_per_m", [](AtmosphereOptions& o, double v) { o.mie_extinction_per_m = v; }, inf},
      {"ozone_absorption_per_m", [](AtmosphereOptions& o, double v) { o.ozone_absorption_per_m[0] = v; }, -1e-9},
      {"ozone_absorption_per_m", [](AtmosphereOptions& o, double v) { o.ozone_absorption_per_m[1] = v; }, nan},
      {"rayleigh_scale_height_m", [](AtmosphereOptions& o, double v) { o.rayleigh_scale_height_m = v; }, 0.0},
      {"mie_scale_height_m", [](AtmosphereOptions& o, double v) { o.mie_scale_height_m = v; }, nan},
      {"planet_radius_m", [](AtmosphereOptions& o, double v) { o.planet_radius_m = v; }, -1.0},
      {"atmosphere_top_m", [](AtmosphereOptions& o, double v) { o.atmosphere_top_m = v; }, 6000e3},
      {"observer_altitude_m", [](AtmosphereOptions& o, double v) { o.observer_altitude_m = v; }, 70e3},
      {"observer_altitude_m", [](AtmosphereOptions& o, double v) { o.observer_altitude_m = v; }, -1.0},
      {"ozone_width_m", [](AtmosphereOptions& o, double v) { o.ozone_width_m = v; }, 0.0},
      {"sun_illuminance_lux", [](AtmosphereOptions& o, double v) { o.sun_illuminance_lux = v; }, nan},
      {"view_steps", [](AtmosphereOptions& o, double v) { o.view_steps = static_cast<int>(v); }, 0.0},
      {"sun_steps", [](AtmosphereOptions& o, double v) { o.sun_steps = static_cast<int>(v); }, -3.0},
      {"azimuth_samples", [](AtmosphereOptions& o, double v) { o.azimuth_samples = static_cast<int>(v); }, 0.0},
  };
  for (const Case& c : cases) {
    AtmosphereOptions o;
    c.edit(o, c.value);
    why.clear();
    EXPECT_FALSE(o.IsValid(&why)) << c.field << " = " << c.value;
    EXPECT_NE(why.find(c.field), std::string::npos) << why;
  }
}

TEST(AtmosphereBake, BakeThrowsOnInvalidInput) {
  AtmosphereOptions bad;
  bad.rayleigh_scattering_per_m[0] = -1.0;
  SkyLuts luts;
  luts.Resize(LutGrid{});
  EXPECT_THROW(render::BakeSingleScattering(bad, luts), Error);
  SkyLuts unsized;  // grid set but tables never resized
  EXPECT_THROW(render::BakeSingleScattering(AtmosphereOptions{}, unsized), Error);
}

}  // namespace
}  // namespace skycal
