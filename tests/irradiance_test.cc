// Irradiance on a diffuse ball (render/irradiance.h): quadrature identities on uniform
// skies, the analytic sun term, SH-9 against quadrature (exact cases, the clamped-cosine
// truncation bound, the default preset) and CPU vs Vulkan predictions.
#include "skycal/render/irradiance.h"

#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "probe_predict_verb.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

using namespace skycal;
using render::Dir3;
using render::Rgb;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kW = 512, kH = 256;
// Row spacing of the node-centred lat-long grid.
const double kDlat = kPi / (kH - 1);

ImageRGB UniformSky(double l, bool lower_half) {
  ImageRGB img(kW, kH);
  for (int y = 0; y < kH; ++y) {
    const bool upper = latlong::Latitude(y, kH) > 0.0;
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = (upper || lower_half) ? static_cast<float>(l) : 0.0f;
  }
  return img;
}

double Dot(const Dir3& a, const Dir3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Tolerance of the quadrature on the uniform skies. PixelSolidAngle gives each row its
// exact band area, and with an even height the horizon is a band boundary, so the
// hemisphere's solid angle is exact. For the up normal the integrand over a band [a, b]
// centred on c is sin(lat) d(sin lat); the row takes sin(c) (sin b - sin a) against the
// exact (sin b - sin a)(sin a + sin b)/2 = (sin b - sin a) sin(c) cos(h/2): the quadrature
// is (exact band)/cos(h/2), except the pole row (half band [pi/2 - h/2, pi/2], sin c = 1):
// E/(pi L) = 2 [(1/2 - sin^2(h/2)/2)/cos(h/2) + 1 - cos(h/2)], ~1 + h^2/8 (1.9e-5 at 256 rows). Tilted
// normals add the kink of max(0, n.w) inside cells and the trapezoid in longitude, both
// O(h^2) with constants of order one: we allow h^2 (1.5e-4), 8x the up-normal error.
const double kQuadTol = kDlat * kDlat;

}  // namespace

TEST(Irradiance, HalfUniformSkyUpNormalIsPiLTimesCosHalfRow) {
  const double l = 1234.5;
  const ImageRGB sky = UniformSky(l, false);
  const Rgb e = render::IrradianceQuadrature(sky, Dir3{0, 1, 0});
  for (int c = 0; c < 3; ++c) {
    // 1e-12: double summation of 131k terms (float L is exact: 1234.5 is representable).
    const double hh = 0.5 * kDlat;
    const double expected = 2.0 * ((0.5 - 0.5 * std::sin(hh) * std::sin(hh)) / std::cos(hh) + 1.0 - std::cos(hh));
    EXPECT_NEAR(e[c] / (kPi * l), expected, 1e-12);
    EXPECT_NEAR(e[c] / (kPi * l), 1.0, kDlat * kDlat / 8.0 + 1e-12);
  }
}

TEST(Irradiance, HalfUniformSkyTiltedNormalsSeeTheSkyViewFactor) {
  // Upper hemisphere L, black ground: E(n) = pi L (1 + n_y) / 2 (pi L for n = up).
  const double l = 2.0;
  const ImageRGB sky = UniformSky(l, false);
  const auto normals = render::FibonacciSphere(200);
  const auto e = render::IrradianceQuadrature(sky, normals);
  double worst = 0.0;
  for (size_t i = 0; i < normals.size(); ++i) {
    const double expected = kPi * l * 0.5 * (1.0 + normals[i][1]);
    // Relative to pi L (a normal facing down sees almost nothing).
    worst = std::max(worst, std::abs(e[i][1] - expected) / (kPi * l));
  }
  std::cout << "[irradiance] half sky, 200 normals: max |E - pi L (1+n_y)/2| / (pi L) = " << worst << " (tol " << kQuadTol
            << ")\n";
  EXPECT_LT(worst, kQuadTol);
}

TEST(Irradiance, FullUniformSphereGivesPiLForEveryNormal) {
  const double l = 3.0;
  const ImageRGB sky = UniformSky(l, true);
  const auto normals = render::FibonacciSphere(200);
  const auto e = render::IrradianceQuadrature(sky, normals, 2);
  double worst = 0.0;
  for (size_t i = 0; i < normals.size(); ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(e[i][c] / (kPi * l) - 1.0));
    // Single-normal and batch versions agree exactly (same summation order).
    if (i % 25 == 0) {
      EXPECT_EQ(render::IrradianceQuadrature(sky, normals[i])[0], e[i][0]);
    }
  }
  std::cout << "[irradiance] full sphere, 200 normals: max |E/(pi L) - 1| = " << worst << " (tol " << kQuadTol << ")\n";
  EXPECT_LT(worst, kQuadTol);
}

TEST(Irradiance, SunTermIsCosineAndOffWhenHidden) {
  const Rgb e_sun = {1e5, 9e4, 8e4};
  const Dir3 s = latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0);
  for (const Dir3& n : render::FibonacciSphere(64)) {
    const Rgb e = render::SunIrradiance(e_sun, s, n, true);
    const double c = std::max(0.0, Dot(n, s));
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(e[k], e_sun[k] * c);
    EXPECT_EQ(render::SunIrradiance(e_sun, s, n, false)[0], 0.0);
  }
  // Up normal: E_sun sin(elevation).
  EXPECT_NEAR(render::SunIrradiance(e_sun, s, Dir3{0, 1, 0}, true)[0], 1e5 * 0.5, 1e-9);
  const Rgb ball = render::BallRadiance({kPi, 2 * kPi, 0}, 0.5);
  EXPECT_DOUBLE_EQ(ball[0], 0.5);
  EXPECT_DOUBLE_EQ(ball[1], 1.0);
}

TEST(Irradiance, Sh9IsExactForUniformSkies) {
  // Full sphere: only L00. Half sky: the step's even bands above 0 vanish and the
  // clamped-cosine kernel has A_l = 0 for odd l > 1, so SH-9 irradiance is exact too.
  for (bool full : {true, false}) {
    const ImageRGB sky = UniformSky(5.0, full);
    const auto sh = render::ProjectSh9(sky);
    const auto normals = render::FibonacciSphere(100);
    const auto q = render::IrradianceQuadrature(sky, normals);
    double worst = 0.0;
    for (size_t i = 0; i < normals.size(); ++i) {
      const double analytic = full ? 5.0 * kPi : 5.0 * kPi * 0.5 * (1.0 + normals[i][1]);
      const Rgb e = render::ShIrradiance(sh, normals[i]);
      EXPECT_NEAR(e[0], analytic, kQuadTol * 5.0 * kPi) << (full ? "full" : "half") << " normal " << i;
      worst = std::max(worst, std::abs(e[0] - q[i][0]) / (5.0 * kPi));
    }
    std::cout << "[irradiance] SH-9 vs quadrature, uniform " << (full ? "sphere" : "half sky") << ": max err / (pi L) = " << worst
              << "\n";
    EXPECT_LT(worst, 2.0 * kQuadTol);  // both are within kQuadTol of the analytic value
  }
}

TEST(Irradiance, Sh9OfOneBrightDirectionHasTheClampedCosineTruncationError) {
  // One pixel carrying illuminance Phi: the quadrature gives exactly Phi max(0, n.s), SH-9
  // gives Phi (3/32 + c/2 + 15/32 c^2) (R&H 2001 band constants). The error
  // f(c) - max(0, c) is 3/32 at c = 0 (its largest: 3/32 = 0.0298 pi), -0.0396 at
  // c = +-8/15 and 1/16 at c = +-1; normals at c = 0 and +-1 are added so both are hit.
  ImageRGB sky(kW, kH);
  const int px = 100, py = 60;
  const double phi = 1e5;
  const double dw = latlong::PixelSolidAngle(px, py, kW, kH);
  for (int c = 0; c < 3; ++c) sky.at(px, py, c) = static_cast<float>(phi / dw);
  const double phi_f = static_cast<double>(static_cast<float>(phi / dw)) * dw;  // float-rounded Phi
  const Dir3 s = latlong::PixelDirection(px, py, kW, kH);
  const auto sh = render::ProjectSh9(sky);
  std::vector<Dir3> normals = render::FibonacciSphere(2000);
  normals.push_back(s);
  normals.push_back({-s[0], -s[1], -s[2]});
  const double hz = std::hypot(s[0], s[2]);
  normals.push_back({s[2] / hz, 0.0, -s[0] / hz});  // perpendicular to s: c = 0
  double at_one = 0.0;
  const auto q = render::IrradianceQuadrature(sky, normals);
  double worst = 0.0;
  for (size_t i = 0; i < normals.size(); ++i) {
    const double c = Dot(normals[i], s);
    EXPECT_NEAR(q[i][0], phi_f * std::max(0.0, c), 1e-9 * phi);
    const double e = render::ShIrradiance(sh, normals[i])[0];
    EXPECT_NEAR(e, phi_f * (3.0 / 32.0 + c / 2.0 + 15.0 / 32.0 * c * c), 1e-9 * phi);
    worst = std::max(worst, std::abs(e - q[i][0]) / phi_f);
    if (std::abs(std::abs(c) - 1.0) < 1e-12) at_one = std::max(at_one, std::abs(e - q[i][0]) / phi_f);
  }
  std::cout << "[irradiance] SH-9, one bright direction: max |E_sh - E_q| / Phi = " << worst << " (bound 3/32), at n = +-s " << at_one
            << " (1/16)\n";
  EXPECT_NEAR(worst, 3.0 / 32.0, 1e-9);  // the bound, attained at c = 0
  EXPECT_NEAR(at_one, 1.0 / 16.0, 1e-9);
}

TEST(Irradiance, DefaultPresetPredictionAndCpuVulkanParity) {
  const render::Preset preset = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  const Dir3 sun = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
  std::vector<Dir3> normals = {{0, 1, 0}};
  for (const auto& n : render::FibonacciSphere(64)) normals.push_back(n);
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const auto pv = render::PredictProbe(preset, sun, normals, 0.18, *vulkan, 512);
  const auto pc = render::PredictProbe(preset, sun, normals, 0.18, *cpu, 512);
  std::cout << "[irradiance] default preset, sun 35 deg: E(up) = " << pv.irradiance[0][0] << ", " << pv.irradiance[0][1] << ", "
            << pv.irradiance[0][2] << " lux (sky " << pv.sky_quadrature[0][1] << "); SH-9 sky error max " << pv.sh_max_rel_error
            << " rms " << pv.sh_rms_rel_error << "; total max " << pv.sh_total_max_rel_error << " rms " << pv.sh_total_rms_rel_error
            << "\n";
  ::testing::Test::RecordProperty("sh_sky_max_rel_error", std::to_string(pv.sh_max_rel_error));
  ::testing::Test::RecordProperty("sh_sky_rms_rel_error", std::to_string(pv.sh_rms_rel_error));
  EXPECT_TRUE(pv.sun_visible);
  // Sanity of the prediction: the up normal sees the sun term E_sun sin(35 deg) plus sky.
  const double sun_up = pv.sun_illuminance[1] * std::sin(35.0 * kPi / 180.0);
  EXPECT_NEAR(pv.irradiance[0][1] - pv.sky_quadrature[0][1], sun_up, 1e-9 * sun_up);
  EXPECT_GT(pv.sky_quadrature[0][1], 0.0);
  EXPECT_NEAR(pv.ball_radiance[0][1], 0.18 / kPi * pv.irradiance[0][1], 1e-9 * pv.irradiance[0][1]);
  // A smooth clear sky: SH-9 is a few percent off at most (recorded above).
  EXPECT_LT(pv.sh_max_rel_error, 0.1);
  EXPECT_LT(pv.sh_total_max_rel_error, pv.sh_max_rel_error + 1e-12);

  // CPU vs Vulkan: 1e-4 relative. The renders agree per pixel to the parity test's float
  // tolerance (~1e-5 relative); irradiance averages those differences.
  double worst = 0.0;
  for (size_t i = 0; i < normals.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::abs(pv.irradiance[i][c] - pc.irradiance[i][c]) / pc.irradiance[i][c]);
      worst = std::max(worst, std::abs(pv.ball_radiance[i][c] - pc.ball_radiance[i][c]) / pc.ball_radiance[i][c]);
    }
  }
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(pv.sh[k][c] - pc.sh[k][c]) / std::max(std::abs(pc.sh[0][c]), 1e-30));
  std::cout << "[irradiance] CPU vs Vulkan prediction: max rel diff " << worst << "\n";
  EXPECT_LT(worst, 1e-4);
}

TEST(Irradiance, RejectsBadInput) {
  EXPECT_THROW(render::IrradianceQuadrature(ImageRGB(1, 1), Dir3{0, 1, 0}), Error);
  EXPECT_THROW(render::IrradianceQuadrature(UniformSky(1.0, true), Dir3{0, 0, 0}), Error);
  EXPECT_THROW(render::FibonacciSphere(0), Error);
}

TEST(ProbePredictVerb, ImplReturnsUpNormalShAndErrors) {
  cli::ProbePredictOptions o;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));  // no sun direction
  o.sun_elevation_deg = 35.0;
  o.sun_azimuth_deg = 20.0;
  o.normals = 8;
  o.backend = render::Backend::kCpu;
  ASSERT_TRUE(o.IsValid(&why)) << why;
  const nlohmann::json j = cli::RunProbePredictImpl(o);
  EXPECT_EQ(j["normals"].size(), 9u);
  EXPECT_EQ(j["sh9_radiance"].size(), 9u);
  EXPECT_GT(j["up"]["irradiance_lux"][1].get<double>(), j["up"]["sky_irradiance_lux"][1].get<double>());
  EXPECT_LT(j["sh9_vs_quadrature"]["sky_max_rel"].get<double>(), 0.1);
  o.albedo = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--albedo"), std::string::npos);
  o.albedo = 0.5;
  o.width = 7;
  EXPECT_FALSE(o.IsValid(&why));
}
