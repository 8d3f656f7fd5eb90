// The game-vs-photo numbers (core/appearance.h): identities, exact values for known changes,
// and the property the appearance error exists for: clouds moved in azimuth cost nothing
// there while the per-pixel error sees them twice.
#include <gtest/gtest.h>

#include <cmath>

#include "skycal/core/appearance.h"
#include "skycal/core/error.h"
#include "skycal/core/luminance.h"

namespace skycal::appearance {
namespace {

constexpr int kW = 128, kH = 64;

// A gray sky brightening towards the horizon, with two bright clouds (columns 10-21,
// rows 8-13 and 20-25): away from the seam columns, whose solid angles differ.
ImageRGB Sky(int cloud_shift = 0) {
  ImageRGB im(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 1000.0f + 40.0f * y;
  for (int y : {8, 9, 10, 11, 12, 13, 20, 21, 22, 23, 24, 25})
    for (int x = 10; x < 22; ++x)
      for (int c = 0; c < 3; ++c) im.at(x + cloud_shift, y, c) = 9000.0f;
  return im;
}

TEST(Appearance, AnImageAgainstItselfIsZero) {
  const ImageRGB p = Sky();
  const Comparison c = Compare(p, p, {}, Options{});
  EXPECT_EQ(c.per_pixel_log_rmse, 0.0);
  EXPECT_EQ(c.appearance_error, 0.0);
  EXPECT_EQ(c.bands_compared, 9);  // 0-90 degrees in 10-degree bands
  EXPECT_EQ(c.sky_pixels, kW * (kH / 2));  // rows 0..31 are at or above 0 degrees
}

TEST(Appearance, AnExposureOffsetIsLnKInBothNumbers) {
  const ImageRGB p = Sky();
  ImageRGB g = p;
  for (float& v : g.pixels) v *= 2.0f;
  const Comparison c = Compare(p, g, {}, Options{});
  EXPECT_NEAR(c.per_pixel_log_rmse, std::log(2.0), 1e-6);
  // Three luminance quantiles move by ln 2, the two chromaticities not at all.
  EXPECT_NEAR(c.appearance_error, std::log(2.0) * std::sqrt(3.0 / 5.0), 1e-6);
}

TEST(Appearance, CloudsMovedInAzimuthCostNothingInAppearance) {
  const Comparison c = Compare(Sky(), Sky(60), {}, Options{});
  EXPECT_EQ(c.appearance_error, 0.0);
  // Wrong in 2 x 144 pixels by ln(9000 / (1000 + 40 y)): large per pixel.
  EXPECT_GT(c.per_pixel_log_rmse, 0.3);
}

TEST(Appearance, ABlueShiftOnAGraySkyIsExact) {
  const ImageRGB p = Sky();
  ImageRGB g = p;
  const double k = std::exp(0.2);
  for (size_t i = 2; i < g.pixels.size(); i += 3) g.pixels[i] = static_cast<float>(g.pixels[i] * k);
  const Comparison c = Compare(p, g, {}, Options{});
  // Gray pixels: ln Y moves by ln(1 + w_b (k - 1)), ln(B/G) by 0.2, ln(R/G) not at all.
  const double dy = std::log(1.0 + kRec709LuminanceWeights[2] * (k - 1.0));
  EXPECT_NEAR(c.appearance_error, std::sqrt((3.0 * dy * dy + 0.04) / 5.0), 1e-6);
  EXPECT_NEAR(c.per_pixel_log_rmse, 0.2 / std::sqrt(3.0), 1e-6);
}

TEST(Appearance, PixelsOutsideTheSkyMaskDoNotCount) {
  const ImageRGB p = Sky();
  ImageRGB g = p;
  std::vector<float> sky(static_cast<size_t>(kW) * kH, 1.0f);
  for (int y = 20; y < 32; ++y)
    for (int x = 40; x < 80; ++x) {
      sky[static_cast<size_t>(y) * kW + x] = 0.0f;
      for (int c = 0; c < 3; ++c) g.at(x, y, c) = 1e9f;  // a building the game does not draw
    }
  const Comparison masked = Compare(p, g, sky, Options{});
  EXPECT_EQ(masked.per_pixel_log_rmse, 0.0);
  EXPECT_EQ(masked.appearance_error, 0.0);
  EXPECT_EQ(masked.sky_pixels, kW * (kH / 2) - 12 * 40);
  const Comparison unmasked = Compare(p, g, {}, Options{});  // the control: it does count there
  EXPECT_GT(unmasked.per_pixel_log_rmse, 1.0);
}

TEST(Appearance, ZerosAreFlooredNotInfinite) {
  const ImageRGB p = Sky();
  ImageRGB g = p;
  for (float& v : g.pixels) v = 0.0f;
  Options o;
  const Comparison c = Compare(p, g, {}, o);
  ASSERT_TRUE(std::isfinite(c.per_pixel_log_rmse));
  // Every game pixel sits at the floor, 1e-4 of the photo's median sky luminance.
  EXPECT_GT(c.per_pixel_log_rmse, std::log(1e4) - 1.0);
  EXPECT_LT(c.per_pixel_log_rmse, std::log(1e4) + 2.5);
}

TEST(Appearance, BadInputNamesWhatIsWrong) {
  const ImageRGB p = Sky();
  try {
    Compare(p, ImageRGB(64, 32), {}, Options{}, "photo.exr", "render.exr");
    FAIL() << "a size mismatch was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("render.exr: 64 x 32 pixels, expected the size of photo.exr (128 x 64)"),
                      std::string::npos) << e.what();
  }
  Options o;
  o.band_deg = 0.0;
  EXPECT_EQ(o.IsValid(), "Options::band_deg = 0: must be in (0, 90] degrees");
  EXPECT_THROW(Compare(p, p, std::vector<float>(10, 1.0f), Options{}), Error);
  EXPECT_THROW(Compare(p, p, std::vector<float>(static_cast<size_t>(kW) * kH, 0.0f), Options{}), Error);
}

// Where the clouds sit: a cloud over the left 64 columns of the upper hemisphere against one over
// the left 32. A pixel's solid angle is its row's band times its column's width, and the first
// and last columns are half wide (core/latlong.h: they are one meridian), so the 128 columns weigh
// 127 units: IoU (31.5 / 63.5), opacity RMS sqrt(32 / 127) (those 32 columns differ by 1);
// identical layers 0 and 1; no cloud, no IoU.
TEST(Appearance, CloudLayersCompareWhereTheCloudsSit) {
  const size_t n = static_cast<size_t>(kW) * kH;
  std::vector<float> half(n, 1.0f), quarter(n, 1.0f);
  for (int y = 0; y < kH / 2; ++y)
    for (int x = 0; x < kW / 2; ++x) {
      half[static_cast<size_t>(y) * kW + x] = 0.0f;
      if (x < kW / 4) quarter[static_cast<size_t>(y) * kW + x] = 0.0f;
    }
  Options o;  // from the horizon up: the upper half of the rows
  const CloudLayerAgreement a = CompareCloudLayers(half, quarter, kW, kH, {}, o);
  EXPECT_EQ(a.pixels, kW * kH / 2);
  ASSERT_TRUE(a.iou.has_value());
  EXPECT_NEAR(*a.iou, 31.5 / 63.5, 1e-12);
  EXPECT_NEAR(a.opacity_rms, std::sqrt(32.0 / 127.0), 1e-12);
  const CloudLayerAgreement same = CompareCloudLayers(half, half, kW, kH, {}, o);
  EXPECT_EQ(same.opacity_rms, 0.0);
  EXPECT_EQ(*same.iou, 1.0);
  const std::vector<float> clear(n, 1.0f);
  EXPECT_FALSE(CompareCloudLayers(clear, clear, kW, kH, {}, o).iou.has_value());
  try {
    CompareCloudLayers(half, std::vector<float>(10, 1.0f), kW, kH, {}, o, "render.exr");
    FAIL() << "a size mismatch was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("render.exr: cloud transmittance of 10 pixels"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skycal::appearance
