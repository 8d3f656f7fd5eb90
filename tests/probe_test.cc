// Gray diffuse probe (capture/probe.h): a synthetic ball lit by an analytic sky and a sun
// of known illuminance, seen by an orthographic camera; the sun is recovered from the
// ball's unclipped pixels (Debevec et al. 2003).
#include "skycal/capture/probe.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "skycal/capture/rig.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::capture {
namespace {

constexpr double kPi = 3.14159265358979323846;
using V3 = std::array<double, 3>;

// Sky radiance L(w) = a + b max(0, w.y) (RGB), everywhere on the sphere (a lit "ground" of
// radiance a below the horizon). E_sky(n) depends only on n.y: tabulated by lat-long
// quadrature over n.y in [-1, 1] and interpolated.
struct AnalyticSky {
  V3 a{0.5, 0.6, 0.9};
  V3 b{0.3, 0.4, 0.8};
  std::vector<V3> table;  // E_sky at n.y = -1 + 2 i / (N - 1)
  static constexpr int kN = 401;

  AnalyticSky() {
    const int W = 512, H = 256;
    std::vector<V3> dirs;
    std::vector<double> weights;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        dirs.push_back(latlong::PixelDirection(x, y, W, H));
        weights.push_back(latlong::PixelSolidAngle(x, y, W, H));
      }
    table.resize(kN);
    for (int i = 0; i < kN; ++i) {
      const double ny = -1.0 + 2.0 * i / (kN - 1);
      const V3 n{std::sqrt(std::max(0.0, 1.0 - ny * ny)), ny, 0.0};
      V3 e{0, 0, 0};
      for (size_t k = 0; k < dirs.size(); ++k) {
        const double cosn = n[0] * dirs[k][0] + n[1] * dirs[k][1] + n[2] * dirs[k][2];
        if (cosn <= 0.0) continue;
        const double up = std::max(0.0, dirs[k][1]);
        for (int c = 0; c < 3; ++c) e[c] += (a[c] + b[c] * up) * cosn * weights[k];
      }
      table[i] = e;
    }
  }
  V3 Irradiance(const V3& n) const {
    const double t = (std::clamp(n[1], -1.0, 1.0) + 1.0) * 0.5 * (kN - 1);
    const int i = std::min(kN - 2, static_cast<int>(t));
    const double f = t - i;
    V3 e;
    for (int c = 0; c < 3; ++c) e[c] = (1 - f) * table[i][c] + f * table[i + 1][c];
    return e;
  }
};

const AnalyticSky& Sky() {
  static const AnalyticSky sky;
  return sky;
}

struct Scene {
  V3 albedo{0.18, 0.18, 0.18};
  V3 e_sun{20.0, 18.0, 15.0};
  V3 sun = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
  // Camera with its back to the sun, looking slightly down at the ball.
  std::array<double, 9> rotation = RotationFromYawPitchRollDeg(200.0, -10.0, 0.0);
  BallCircle circle{321.4, 283.6, 200.0};
  int width = 640, height = 580;
  float background = 0.01f;
  double noise = 0.01;
  double clip = std::numeric_limits<double>::infinity();
  bool sun_on = true;
};

ImageRGB Render(const Scene& s, unsigned seed = 7) {
  ImageRGB img(s.width, s.height);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const auto n = BallNormalAt(s.circle, s.rotation, x, y);
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = s.background;
      if (!n) continue;
      const V3 e = Sky().Irradiance(*n);
      const double cosv = std::max(0.0, (*n)[0] * s.sun[0] + (*n)[1] * s.sun[1] + (*n)[2] * s.sun[2]);
      for (int c = 0; c < 3; ++c) {
        double L = s.albedo[c] / kPi * (e[c] + (s.sun_on ? s.e_sun[c] * cosv : 0.0));
        L *= 1.0 + s.noise * g(rng);
        img.at(x, y, c) = static_cast<float>(std::min(L, s.clip));
      }
    }
  return img;
}

std::vector<V3> SkyAt(const std::vector<ProbeSample>& samples) {
  std::vector<V3> e;
  for (const auto& smp : samples) e.push_back(Sky().Irradiance(smp.normal));
  return e;
}

double MaxRadiance(const ImageRGB& img) {
  double m = 0;
  for (float v : img.pixels) m = std::max(m, static_cast<double>(v));
  return m;
}

TEST(Probe, NormalsFaceTheCamera) {
  Scene s;
  // The ball's centre pixel faces the camera: normal = -(viewing direction) = -R[:,2].
  const auto n = BallNormalAt(s.circle, s.rotation, s.circle.cx, s.circle.cy);
  ASSERT_TRUE(n);
  EXPECT_NEAR((*n)[0], -s.rotation[2], 1e-12);
  EXPECT_NEAR((*n)[1], -s.rotation[5], 1e-12);
  EXPECT_NEAR((*n)[2], -s.rotation[8], 1e-12);
  // The top of the ball in the image points up in the world (camera pitched only 10 deg).
  const auto top = BallNormalAt(s.circle, s.rotation, s.circle.cx, s.circle.cy - 0.999 * s.circle.radius_px);
  ASSERT_TRUE(top);
  EXPECT_GT((*top)[1], 0.9);
  EXPECT_FALSE(BallNormalAt(s.circle, s.rotation, s.circle.cx + 201, s.circle.cy));
}

TEST(Probe, RecoversClippedSun) {
  Scene s;
  // Saturate the sun-facing side: clip at 70% of the ball's peak.
  const double peak = MaxRadiance(Render(s));
  s.clip = 0.7 * peak;
  const ImageRGB img = Render(s);
  ProbeOptions opt;
  opt.clip_level = s.clip;
  const ProbeMeasurement m = MeasureProbe(img, s.rotation, s.circle, opt);
  EXPECT_GT(m.pixels_clipped, 1000);
  EXPECT_TRUE(m.max_luminance_clipped);
  EXPECT_GT(m.samples.size(), 100u);
  for (const auto& smp : m.samples)
    for (int c = 0; c < 3; ++c) EXPECT_LT(smp.radiance[c], s.clip);
  const SunRecovery r = RecoverSun(m.samples, s.albedo, SkyAt(m.samples), s.sun);
  double worst = 0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(r.sun_illuminance[c] / s.e_sun[c] - 1.0));
  std::printf("clipped sun: recovered E_sun = (%.4f, %.4f, %.4f) vs (%.1f, %.1f, %.1f): worst rel err %.4f%%, "
              "sun_fraction %.3f, residual_rms_rel %.4f, %zu samples, %d clipped px\n",
              r.sun_illuminance[0], r.sun_illuminance[1], r.sun_illuminance[2], s.e_sun[0], s.e_sun[1], s.e_sun[2],
              100 * worst, r.sun_fraction, r.residual_rms_rel, m.samples.size(), m.pixels_clipped);
  EXPECT_TRUE(r.visible);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(r.sun_fraction, 0.5);
  EXPECT_LT(r.residual_rms_rel, 0.01);

  // Without rejecting clipped pixels the fit is biased low: the rejection matters.
  const ProbeMeasurement raw = MeasureProbe(img, s.rotation, s.circle, ProbeOptions{});
  const SunRecovery biased = RecoverSun(raw.samples, s.albedo, SkyAt(raw.samples), s.sun);
  EXPECT_LT(biased.sun_illuminance[1], 0.97 * s.e_sun[1]);
}

TEST(Probe, OccludedSunIsNotVisible) {
  Scene s;
  s.sun_on = false;
  const ImageRGB img = Render(s);
  const ProbeMeasurement m = MeasureProbe(img, s.rotation, s.circle);
  const SunRecovery r = RecoverSun(m.samples, s.albedo, SkyAt(m.samples), s.sun);
  std::printf("occluded sun: fitted E_sun = (%.4f, %.4f, %.4f), sun_fraction %.4f\n", r.fitted_sun_illuminance[0],
              r.fitted_sun_illuminance[1], r.fitted_sun_illuminance[2], r.sun_fraction);
  EXPECT_FALSE(r.visible);
  EXPECT_LT(r.sun_fraction, 0.05);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(r.sun_illuminance[c], 0.0);
    EXPECT_LT(r.fitted_sun_illuminance[c], 0.05 * s.e_sun[c]);
  }
  // The Forza statistic drops to the ambient level.
  Scene lit;
  const ProbeMeasurement ml = MeasureProbe(Render(lit), lit.rotation, lit.circle);
  EXPECT_GT(ml.max_luminance, 3.0 * m.max_luminance);
  EXPECT_FALSE(ml.max_luminance_clipped);
}

TEST(Probe, BallOutsideImageIsAnError) {
  Scene s;
  const ImageRGB img = Render(s);
  for (const BallCircle c : {BallCircle{100.0, 283.6, 200.0}, BallCircle{321.4, 283.6, 400.0},
                             BallCircle{1000.0, 1000.0, 50.0}}) {
    try {
      MeasureProbe(img, s.rotation, c);
      ADD_FAILURE() << "no error for a circle outside the image";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("outside the 640x580 image"), std::string::npos) << e.what();
    }
  }
}

TEST(Probe, FullyClippedBallIsAnError) {
  Scene s;
  s.clip = 0.01;  // everything on the ball sits at the clamp
  const ImageRGB img = Render(s);
  ProbeOptions opt;
  opt.clip_level = 0.01;
  try {
    MeasureProbe(img, s.rotation, s.circle, opt);
    ADD_FAILURE() << "no error for a fully clipped ball";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no usable sample"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("clipped"), std::string::npos) << e.what();
  }
  // All-NaN ball too.
  ImageRGB nan_img = Render(Scene{});
  for (int y = 0; y < nan_img.height; ++y)
    for (int x = 0; x < nan_img.width; ++x)
      if (BallNormalAt(s.circle, s.rotation, x, y))
        for (int c = 0; c < 3; ++c) nan_img.at(x, y, c) = std::nanf("");
  EXPECT_THROW(MeasureProbe(nan_img, s.rotation, s.circle), Error);
}

TEST(Probe, SunBehindTheBallIsAnError) {
  Scene s;
  const ProbeMeasurement m = MeasureProbe(Render(s), s.rotation, s.circle);
  const V3 behind{-s.sun[0], -s.sun[1], -s.sun[2]};
  EXPECT_THROW(RecoverSun(m.samples, s.albedo, SkyAt(m.samples), behind), Error);
  EXPECT_THROW(RecoverSun(m.samples, s.albedo, {}, s.sun), Error);
}

TEST(Probe, HoughFindsTheBall) {
  Scene s;
  s.clip = 0.7 * MaxRadiance(Render(s));  // a saturated highlight too
  const ImageRGB img = Render(s);
  const BallCircle c = DetectBall(img);
  std::printf("detected ball (%.2f, %.2f, r %.2f) vs (%.2f, %.2f, r %.2f)\n", c.cx, c.cy, c.radius_px, s.circle.cx,
              s.circle.cy, s.circle.radius_px);
  EXPECT_NEAR(c.cx, s.circle.cx, 2.0);
  EXPECT_NEAR(c.cy, s.circle.cy, 2.0);
  EXPECT_NEAR(c.radius_px, s.circle.radius_px, 2.0);
  // MeasureProbe without a circle detects it.
  ProbeOptions opt;
  opt.clip_level = s.clip;
  const ProbeMeasurement m = MeasureProbe(img, s.rotation, std::nullopt, opt);
  EXPECT_NEAR(m.circle.cx, s.circle.cx, 2.0);

  // Nothing to find in a flat image.
  ImageRGB flat(200, 150);
  for (float& v : flat.pixels) v = 0.3f;
  EXPECT_THROW(DetectBall(flat), Error);
}

}  // namespace
}  // namespace skycal::capture
