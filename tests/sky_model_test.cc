// Analytic identities of the shared model source (CPU instantiation, double) and of the
// rendered images on both backends.
#include <gtest/gtest.h>

#include <ceres/jet.h>

#include <cmath>

#include "../render/src/resolved_sky.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"
#include "test_presets.h"

namespace skycal {
namespace {

using render::Backend;
using render::ModelVariant;

// A LUT source of constant texels, for functions that do not touch the LUTs.
struct ConstantLut {
  template <typename S>
  glsl::Vec3<S> texel(int, int, int) const { return glsl::Vec3<S>(S(1.0)); }
};
using Model = model::SkyModel<double, ConstantLut>;

// 2 pi * integral over mu of phase(mu), on theta = pi t^2 (nodes crowd toward the forward
// peak, whose width is ~(1-g) rad), composite Simpson with n intervals.
template <typename F>
double IntegrateOverSphere(F phase, int n = 200000) {
  auto integrand = [&](double t) {
    const double theta = M_PI * t * t;
    const double dtheta_dt = 2.0 * M_PI * t;
    return phase(theta) * std::sin(theta) * dtheta_dt;
  };
  double sum = integrand(0.0) + integrand(1.0);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * integrand(static_cast<double>(i) / n);
  return 2.0 * M_PI * sum / (3.0 * n);
}

TEST(SkyModel, PhaseFunctionsIntegrateToOne) {
  ConstantLut lut;
  Model m(lut);
  const double rayleigh = IntegrateOverSphere([&](double th) { return m.phase_rayleigh(std::cos(th)); });
  EXPECT_NEAR(rayleigh, 1.0, 1e-9);
  for (double g : {0.0, 0.3, 0.5, 0.76, 0.9, 0.99}) {
    const double mie = IntegrateOverSphere([&](double th) {
      const double mu = std::cos(th);
      const double one_minus_mu = 2.0 * std::sin(0.5 * th) * std::sin(0.5 * th);
      return m.phase_cornette_shanks(mu, one_minus_mu, g);
    });
    EXPECT_NEAR(mie, 1.0, 1e-6) << "g = " << g;
  }
}

TEST(SkyModel, CornetteShanksAtGZeroIsRayleigh) {
  ConstantLut lut;
  Model m(lut);
  for (double mu : {-1.0, -0.3, 0.0, 0.5, 1.0}) {
    EXPECT_NEAR(m.phase_cornette_shanks(mu, 1.0 - mu, 0.0), m.phase_rayleigh(mu), 1e-15);
  }
}

TEST(SkyModel, JetInstantiationGivesExactDerivativeOfPhase) {
  // The shared source compiled with ceres::Jet: d phaseM / d g against a central difference.
  using J = ceres::Jet<double, 1>;
  ConstantLut lut;
  model::SkyModel<J, ConstantLut> mj(lut);
  Model m(lut);
  const double g = 0.8, mu = 0.95;
  const J value = mj.phase_cornette_shanks(J(mu), J(1.0 - mu), J(g, 0));
  const double h = 1e-6;
  const double fd = (m.phase_cornette_shanks(mu, 1.0 - mu, g + h) - m.phase_cornette_shanks(mu, 1.0 - mu, g - h)) / (2 * h);
  EXPECT_NEAR(value.a, m.phase_cornette_shanks(mu, 1.0 - mu, g), 1e-14);
  EXPECT_NEAR(value.v[0], fd, 1e-6 * std::abs(fd));
}

render::RenderRequest Request(double elevation, double azimuth, int w = 256, int h = 128) {
  render::RenderRequest r;
  r.sun_dir = latlong::DirectionFromElevationAzimuthDeg(elevation, azimuth);
  r.width = w;
  r.height = h;
  return r;
}

class BothBackends : public ::testing::TestWithParam<Backend> {
 protected:
  std::unique_ptr<render::SkyRenderer> renderer_ = render::CreateRenderer(GetParam());
};

TEST_P(BothBackends, SymmetricAboutTheSunsVerticalPlane) {
  render::Preset p = testing::RandomPreset(11, ModelVariant::kFfxvIso);
  p.haziness_g = 0.9;
  for (double el : {-10.0, 0.0, 20.0, 65.0}) {
    const ImageRGB img = renderer_->Render(p, Request(el, 0.0));  // sun at longitude 0: column (W-1)/2
    double worst = 0.0;
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) {
        for (int c = 0; c < 3; ++c) {
          const double a = img.at(x, y, c), b = img.at(img.width - 1 - x, y, c);
          worst = std::max(worst, std::abs(a - b) / std::max(std::abs(a), 1e-30));
        }
      }
    }
    // Mirror columns have exactly mirrored directions (integer numerators in the lat-long
    // angles), so only the float sum order could differ: 1e-6 allows a few ulp.
    EXPECT_LT(worst, 1e-6) << "elevation " << el;
  }
}

TEST_P(BothBackends, ContinuousAcrossAzimuthSeam) {
  render::Preset p = testing::RandomPreset(12, ModelVariant::kFfxv);
  const ImageRGB img = renderer_->Render(p, Request(25.0, 170.0));  // sun near the seam
  for (int y = 0; y < img.height; ++y) {
    for (int c = 0; c < 3; ++c) {
      // Columns 0 and W-1 are the same direction (longitude +pi and -pi).
      const double a = img.at(0, y, c), b = img.at(img.width - 1, y, c);
      EXPECT_NEAR(a, b, 1e-5 * std::max(std::abs(a), 1e-30)) << "row " << y;
      // Across the seam (column W-2 -> 0) the step is like any interior step (1 -> 2).
      const double across = std::abs(img.at(img.width - 2, y, c) - a);
      const double inside = std::abs(img.at(2, y, c) - img.at(1, y, c));
      EXPECT_LE(across, 2.0 * inside + 1e-4 * std::abs(a)) << "row " << y;
    }
  }
}

TEST_P(BothBackends, FiniteAndNonNegativeForExtremePresets) {
  for (int k = 0; k < 4; ++k) {
    render::Preset p = testing::RandomPreset(20 + k, k % 2 ? ModelVariant::kFfxvIso : ModelVariant::kFfxv);
    p.haziness_g = k == 0 ? 0.999 : (k == 1 ? 0.0 : 0.9);
    p.overcast_weight = k == 2 ? 1.0 : 0.0;
    if (k == 3) {  // all-zero LUTs and no sun: a black sky, not NaN
      p.luts.Resize(p.luts.grid);
      p.sun_illuminance_lux = 0.0;
    }
    for (double el : {-90.0, -18.0, 0.0, 90.0}) {
      const ImageRGB img = renderer_->Render(p, Request(el, 33.0, 512, 256));
      for (float v : img.pixels) {
        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << "preset " << k << " elevation " << el << " value " << v;
      }
    }
  }
}

TEST_P(BothBackends, OvercastSkyFollowsCieFormula) {
  render::Preset p = testing::RandomPreset(30, ModelVariant::kFfxv);
  p.overcast_weight = 1.0;
  p.overcast_zenith_cd_m2 = 3000.0;
  render::RenderRequest r = Request(30.0, 0.0, 256, 129);  // odd height: a row on the horizon
  r.sun_disc = false;
  const ImageRGB img = renderer_->Render(p, r);
  EXPECT_NEAR(img.at(10, 0, 1), 3000.0, 3000.0 * 1e-6);        // zenith: L_z
  EXPECT_NEAR(img.at(10, 64, 1), 1000.0, 1000.0 * 1e-5);       // horizon: L_z / 3
  const double el = latlong::Latitude(32, 129);                  // 45 deg
  EXPECT_NEAR(img.at(77, 32, 2), 3000.0 * (1.0 + 2.0 * std::sin(el)) / 3.0, 1e-2);
}

INSTANTIATE_TEST_SUITE_P(Backends, BothBackends, ::testing::Values(Backend::kCpu, Backend::kVulkan),
                         [](const auto& info) { return std::string(render::ToString(info.param)); });

TEST(SkyModel, ContinuousAtTheHorizon) {
  // The LUT column coordinate sqrt(view.y) is continuous at view.y = 0; the radiance just
  // above the horizon converges to the horizon value like sqrt(view.y).
  render::Preset p = testing::RandomPreset(40, ModelVariant::kFfxvIso);
  render::RenderRequest r = Request(12.0, 0.0);
  const render::SkyParamsD params = render::ResolveSkyParams(p, r);
  render::CpuLutSource src{&p.luts};
  render::CpuSkyModel m(src);
  const glsl::Vec3<double> at_horizon(std::sin(2.0), 0.0, std::cos(2.0));
  const auto l0 = m.sky_radiance(at_horizon, params);
  for (double eps : {1e-4, 1e-6, 1e-8}) {
    const glsl::Vec3<double> v(std::sin(2.0) * std::cos(eps), std::sin(eps), std::cos(2.0) * std::cos(eps));
    const auto l = m.sky_radiance(v, params);
    // The column coordinate moves by sqrt(eps) * (n_gamma - 1) texels; the test LUTs at most
    // double between nodes, so the radiance moves by at most that fraction of 2 * l0.
    EXPECT_NEAR(l.x, l0.x, 2.0 * std::sqrt(eps) * (p.luts.grid.n_gamma - 1) * l0.x) << "eps " << eps;
  }
}

TEST(SkyModel, SunDiscIntegratesToItsIlluminance) {
  // E = integral of the disc radiance over its solid angle, with limb darkening.
  render::Preset p = testing::RandomPreset(50, ModelVariant::kFfxv);
  p.sun_angular_radius_deg = 0.5;
  p.sun_limb_darkening = 0.6;
  render::RenderRequest r = Request(40.0, 10.0);
  const render::SkyParamsD params = render::ResolveSkyParams(p, r);
  render::CpuLutSource src{&p.luts};
  render::CpuSkyModel m(src);
  // Polar grid around the sun direction.
  const auto s = r.sun_dir;
  const auto e1 = latlong::Normalized({s[2], 0.0, -s[0]}, "e1");
  const std::array<double, 3> e2 = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  const double R = p.sun_angular_radius_deg * M_PI / 180.0;
  const int nr = 4000, nphi = 64;
  double e_green = 0.0;
  for (int i = 0; i < nr; ++i) {
    const double a = (i + 0.5) * R / nr;
    for (int j = 0; j < nphi; ++j) {
      const double phi = (j + 0.5) * 2.0 * M_PI / nphi;
      const double ca = std::cos(a), sa = std::sin(a);
      glsl::Vec3<double> v(ca * s[0] + sa * (std::cos(phi) * e1[0] + std::sin(phi) * e2[0]),
                           ca * s[1] + sa * (std::cos(phi) * e1[1] + std::sin(phi) * e2[1]),
                           ca * s[2] + sa * (std::cos(phi) * e1[2] + std::sin(phi) * e2[2]));
      e_green += m.sun_disc_radiance(v, params).y * std::sin(a) * (R / nr) * (2.0 * M_PI / nphi);
    }
  }
  const double expected = p.sun_illuminance_lux * p.sun_tint_rgb[1] * render::SunTransmittance(p.luts, 50.0 * M_PI / 180.0)[1];
  // 2e-4: the normalisation E = L0 * Omega * (1 - u/3) treats the disc as flat (error ~R^2/4).
  EXPECT_NEAR(e_green / expected, 1.0, 2e-4);
}

TEST(SkyModel, LitGroundFromUniformSky) {
  // An isotropic-only sky of radiance L gives E_sky = pi L on the ground plane, so the
  // ground shows albedo/pi * (E_sun cos(zenith) + pi L).
  render::Preset p = testing::RandomPreset(60, ModelVariant::kFfxvIso);
  std::fill(p.luts.rayleigh.begin(), p.luts.rayleigh.end(), 0.0f);
  std::fill(p.luts.mie.begin(), p.luts.mie.end(), 0.0f);
  const double L = 2000.0;
  std::fill(p.luts.isotropic.begin(), p.luts.isotropic.end(), static_cast<float>(4.0 * M_PI * L));
  p.ground_albedo = 0.25;
  render::RenderRequest r = Request(30.0, 0.0);
  const render::SkyParamsD params = render::ResolveSkyParams(p, r);
  const double e_sun = p.sun_illuminance_lux * render::SunTransmittance(p.luts, 60.0 * M_PI / 180.0)[0];
  const double expected = 0.25 / M_PI * (e_sun * 0.5 + M_PI * L);
  EXPECT_NEAR(params.ground_radiance.x, expected, 1e-4 * expected);
}

}  // namespace
}  // namespace skycal
