// Star removal (capture/star_removal.h, skycal stars): synthetic stars over a rendered
// twilight sky (sun at -6 degrees: recall, precision, pixels away from stars bit for bit,
// the sky under a star restored, not blurred) and the real night sky through the binary.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "skycal/render/preset.h"
#include "run_binary.h"
#include "skycal/capture/star_removal.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"
#include "skycal/testing/synthetic_stars.h"
#include "test_util.h"

namespace skycal {
namespace {

const std::string kRoot = SKYCAL_SOURCE_DIR;

struct TwilightCase {
  ImageRGB sky, starry;
  std::vector<testing::SyntheticStar> stars;
};

// The bundled clear preset at sun elevation -6 deg (civil dusk), 256x128, 0.5% noise, 60
// stars 2-30x the sky between elevations 10 and 67 deg.
TwilightCase MakeTwilight() {
  TwilightCase t;
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(-6.0, 40.0);
  req.width = 256;
  req.height = 128;
  t.sky = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(kRoot + "/datasets/presets/default_clear.json"), req);
  std::mt19937 rng(6);
  std::normal_distribution<float> noise(0.0f, 0.005f);
  for (float& v : t.sky.pixels) v *= 1.0f + noise(rng);
  t.starry = t.sky;
  t.stars = testing::AddStars(&t.starry, 60, 16, 56, 2.0, 30.0, 8, 11);
  return t;
}

bool NearAStar(const std::vector<testing::SyntheticStar>& stars, int x, int y, double px) {
  for (const auto& s : stars)
    if (std::abs(x - s.x) <= px && std::abs(y - s.y) <= px) return true;
  return false;
}

TEST(StarRemoval, SyntheticStarsOverATwilightSky) {
  const TwilightCase t = MakeTwilight();
  ASSERT_EQ(t.stars.size(), 60u);
  double sky_min = 1e30;
  for (float v : t.sky.pixels) sky_min = std::min<double>(sky_min, v);
  ASSERT_GT(sky_min, 0.0) << "the twilight render must be a lit sky";
  const capture::StarRemovalResult r = capture::RemoveStars(t.starry, {});
  // Recall: stars whose centre pixel was replaced.
  int found = 0;
  for (const auto& s : t.stars) found += r.mask[static_cast<size_t>(std::lround(s.y)) * 256 + std::lround(s.x)] == 1;
  const double recall = static_cast<double>(found) / t.stars.size();
  const double precision = r.stars > 0 ? static_cast<double>(found) / r.stars : 0.0;
  std::printf("twilight: %d stars removed, recall %.3f, precision %.3f, %lld pixels replaced, noise %.3g\n", r.stars,
              recall, precision, r.pixels_replaced, r.noise_sigma);
  // Measured 1.0 and 1.0 (all 60 stars are >= 2x the sky): margins for other compilers' rounding.
  EXPECT_GE(recall, 0.95);
  EXPECT_GE(precision, 0.98);
  // Pixels farther than 3 px from every star: bit for bit; the sky under a star restored to
  // within the measured level (below).
  long long far = 0;
  std::vector<double> restored;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c) {
        if (!NearAStar(t.stars, x, y, 3.0)) {
          ++far;
          ASSERT_EQ(r.image.at(x, y, c), t.starry.at(x, y, c)) << "pixel " << x << "," << y << " far from stars changed";
        } else if (r.mask[static_cast<size_t>(y) * 256 + x]) {
          restored.push_back(std::abs(r.image.at(x, y, c) / t.sky.at(x, y, c) - 1.0));
        }
      }
  EXPECT_GT(far, 3LL * 256 * 128 * 9 / 10);
  ASSERT_FALSE(restored.empty());
  std::sort(restored.begin(), restored.end());
  std::printf("restored: median %.4f, p95 %.4f relative error\n", restored[restored.size() / 2], restored[restored.size() * 95 / 100]);
  // Measured 1.2% / 8.4% (the 256x128 render changes by up to 8% per row near the horizon;
  // a square-window median gave 3.2% / 11.6%): margins of ~1.5x.
  EXPECT_LT(restored[restored.size() / 2], 0.02);
  EXPECT_LT(restored[restored.size() * 95 / 100], 0.12);
  // Control: a stricter threshold (60 sigma) misses the faint ones, so recall is measured, not given.
  capture::StarRemovalOptions strict;
  strict.threshold_sigma = 60.0;
  strict.min_contrast = 6.0;
  const capture::StarRemovalResult s = capture::RemoveStars(t.starry, strict);
  EXPECT_LT(s.stars, 50);
}

TEST(StarRemoval, ExtendedAndClusteredSourcesStay) {
  ImageRGB img(64, 32);
  for (float& v : img.pixels) v = 0.01f;
  for (int y = 10; y < 16; ++y)
    for (int x = 10; x < 16; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 1.0f;  // a 6x6 "moon": too large
  for (int c = 0; c < 3; ++c) img.at(40, 12, c) = img.at(42, 12, c) = 1.0f;  // two points 2 px apart: clustered
  const capture::StarRemovalResult r = capture::RemoveStars(img, {});
  EXPECT_EQ(r.stars, 0);
  EXPECT_EQ(r.rejected_large, 1);
  EXPECT_EQ(r.rejected_clustered, 2);
  EXPECT_EQ(r.image.pixels, img.pixels);
  capture::StarRemovalOptions bad;
  bad.window_px = 4;
  EXPECT_THROW(capture::RemoveStars(img, bad), Error);
}

// The library names StarRemovalOptions' field and value; `skycal stars` says the flag.
TEST(StarRemoval, OptionsNameTheFieldAndTheVerbTheFlag) {
  capture::StarRemovalOptions bad;
  bad.window_px = 4;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_EQ(why, "StarRemovalOptions::window_px = 4: expected an odd number in [3, 31] pixels");
  testing::ScratchDir dir("stars-flags");
  const auto r = testing::RunSkycal(SKYCAL_BINARY, "stars --reference " + (dir / "night.exr") + " --out " +
                                                       (dir / "clean.exr") + " --star-window 4");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--star-window 4: expected an odd number in [3, 31] pixels"), std::string::npos) << r.err;
  EXPECT_EQ(dir.CountEntries(), 0);
}

// The real night sky (Poly Haven via Blender, 1024x512) through `skycal stars`.
TEST(StarRemoval, RealNightSkyThroughTheBinary) {
  testing::ScratchDir dir("stars");
  const std::string in = kRoot + "/datasets/real/night.exr";
  if (!std::filesystem::exists(in)) GTEST_SKIP() << in << " absent: run datasets/fetch_real_skies.sh";
  const auto r = testing::RunSkycal(SKYCAL_BINARY, "stars --reference " + in + " --out " + (dir / "clean.exr") +
                                                       " --mask-out " + (dir / "stars.exr") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const int count = j["stars_removed"].get<int>();
  std::printf("night.exr: %d stars removed, %lld pixels\n", count, j["pixels_replaced"].get<long long>());
  EXPECT_GT(count, 50);
  const ExrRGB a = ReadExrRGB(in), b = ReadExrRGB(dir / "clean.exr"), m = ReadExrRGB(dir / "stars.exr");
  ASSERT_EQ(b.image.width, a.image.width);
  EXPECT_EQ(b.attributes.floats.at("skycalStarsRemoved"), count);
  // Pixels changed only where the mask says, and nothing farther than 3 px from a masked pixel.
  const int w = a.image.width, h = a.image.height;
  std::vector<uint8_t> near(static_cast<size_t>(w) * h, 0);
  long long masked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (m.image.at(x, y, 0) != 1.0f) continue;
      ++masked;
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx)
          if (y + dy >= 0 && y + dy < h) near[static_cast<size_t>(y + dy) * w + (x + dx + w) % w] = 1;
    }
  EXPECT_EQ(masked, j["pixels_replaced"].get<long long>());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const bool changed = a.image.at(x, y, c) != b.image.at(x, y, c) && !(std::isnan(a.image.at(x, y, c)) && std::isnan(b.image.at(x, y, c)));
        if (changed) {
          ASSERT_EQ(m.image.at(x, y, 0), 1.0f) << "pixel " << x << "," << y << " changed outside the mask";
        }
        if (!near[static_cast<size_t>(y) * w + x]) {
          ASSERT_FALSE(changed);
        }
      }
  // Bad input: exit 1, the file named, nothing written.
  const auto bad = testing::RunSkycal(SKYCAL_BINARY, "stars --reference " + (dir / "missing.exr") + " --out " + (dir / "x.exr") +
                                                         " --mask-out " + (dir / "xm.exr"));
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("missing.exr"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.exr"));
  EXPECT_FALSE(std::filesystem::exists(dir / "xm.exr"));
}

}  // namespace
}  // namespace skycal
