// Degenerate references and starts: a clear error, or a documented finite result, never a
// non-finite preset.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/renderer.h"
#include "test_util.h"

namespace skycal {
namespace {

render::Preset DefaultStart() {
  return render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
}

fit::FitOptions Quiet() {
  fit::FitOptions o;
  o.verbose = false;
  o.sun_dir = latlong::DirectionFromElevationAzimuthDeg(35.0, 10.0);
  return o;
}

// The default preset drawn at Quiet()'s sun (zero ground), width x width/2.
capture::LatLongFrame DefaultRender(int width) {
  render::RenderRequest req;
  req.sun_dir = *Quiet().sun_dir;
  req.width = width;
  req.height = width / 2;
  req.ground = render::GroundMode::kZero;
  capture::LatLongFrame f;
  f.radiance = render::CreateRenderer(render::Backend::kCpu)->Render(DefaultStart(), req);
  return f;
}

void ExpectFinite(const render::Preset& p) {
  for (const auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
    for (float v : *t) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
  EXPECT_TRUE(std::isfinite(p.haziness_g));
  EXPECT_TRUE(std::isfinite(p.overcast_zenith_cd_m2));
}

TEST(FitDegenerate, ConstantColourSkyIsFittedByTheIsotropicTerm) {
  // One colour everywhere: ffxv-iso's isotropic table represents it exactly (the
  // phase-weighted tables may go to their floor); the result is finite and fits.
  testing::ScratchDir dir("fit-constant");
  capture::LatLongFrame f;
  f.radiance = ImageRGB(256, 128);
  for (size_t i = 0; i < f.radiance.pixels.size(); i += 3) {
    f.radiance.pixels[i] = 1200.0f;
    f.radiance.pixels[i + 1] = 1000.0f;
    f.radiance.pixels[i + 2] = 800.0f;
  }
  capture::WriteLatLongFrame(dir / "constant.exr", f);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const fit::FitResult r = fit::FitSky({fit::LoadReference(dir / "constant.exr", Quiet())}, DefaultStart(), Quiet(), *cpu);
  ExpectFinite(r.preset);
  EXPECT_LT(r.references[0].errors.rel_rmse, 1e-3);
}

TEST(FitDegenerate, ValidPixelsInOneRowGiveAFiniteFit) {
  // Every pixel invalid (NaN) but one image row at 20 deg elevation: the row's LUT
  // columns are fitted, the rest keep the start's shape; the result is finite and fits
  // the row.
  testing::ScratchDir dir("fit-one-row");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  capture::LatLongFrame f = DefaultRender(256);
  const int keep = 128 / 2 - 1 - static_cast<int>(std::lround(20.0 / 180.0 * 127.0));
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c)
        if (y != keep) f.radiance.at(x, y, c) = std::numeric_limits<float>::quiet_NaN();
  capture::WriteLatLongFrame(dir / "row.exr", f);
  const fit::Reference ref = fit::LoadReference(dir / "row.exr", Quiet());
  EXPECT_GT(ref.counts.sky, 200);
  EXPECT_EQ(ref.counts.sky + ref.counts.sun_cone, 256);
  const fit::FitResult r = fit::FitSky({ref}, DefaultStart(), Quiet(), *cpu);
  ExpectFinite(r.preset);
  EXPECT_LT(r.references[0].errors.rel_rmse, 1e-3);
}

TEST(FitDegenerate, StartPresetWithNanIsRefusedNamingTheTable) {
  testing::ScratchDir dir("fit-nan-start");
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  capture::WriteLatLongFrame(dir / "ref.exr", DefaultRender(128));
  const fit::Reference ref = fit::LoadReference(dir / "ref.exr", Quiet());
  render::Preset nan_start = DefaultStart();
  nan_start.luts.mie[100] = std::numeric_limits<float>::quiet_NaN();
  try {
    fit::FitSky({ref}, nan_start, Quiet(), *cpu);
    FAIL() << "a NaN LUT entry in the start was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mie"), std::string::npos) << e.what();
  }
  // A zero entry is documented: it starts at the floor (5% of the tables' mean).
  render::Preset zero_start = DefaultStart();
  std::fill(zero_start.luts.rayleigh.begin(), zero_start.luts.rayleigh.begin() + 300, 0.0f);
  const fit::FitResult r = fit::FitSky({ref}, zero_start, Quiet(), *cpu);
  ExpectFinite(r.preset);
  EXPECT_LT(r.references[0].errors.rel_rmse, 1e-3);
}

}  // namespace
}  // namespace skycal
