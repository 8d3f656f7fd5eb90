// Automatic sky segmentation (capture/sky_segmentation.h): a synthetic scene with a known
// answer (a building standing on the horizon, a dark cloud floating above it), the real
// skies against their hand masks (precision / recall floors from
// bench/results/sky_segmentation.md), option validation, and `skycal mask` on bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <unistd.h>
#include <utility>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/render/renderer.h"

namespace skycal {
namespace {

const std::string kRoot = SKYCAL_SOURCE_DIR;

// The bundled clear sky at sun 30 deg, 256x128, no disc.
ImageRGB ClearSky(const std::array<double, 3>& sun) {
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = 256;
  req.height = 128;
  req.sun_disc = false;
  const render::Preset p = render::LoadPreset(kRoot + "/datasets/presets/default_clear.json");
  return render::CreateRenderer(render::Backend::kCpu)->Render(p, req);
}

// The first row at or below elevation 0.
int HorizonRow(int h) { return static_cast<int>(std::ceil(latlong::RowOfLatitude(0.0, h))); }

// A grey cumulus bank over columns [20, 120) and the 12 rows above the horizon row: 0.3 of
// the sky at its top (~17 deg), fading to 0.9 in the lowest row (0.7 deg), a third of its
// pixels 0.7 of that (texture: ln(0.9 x 0.7) = -0.46 in the lowest row).
void PaintHazyBank(ImageRGB* img, int horizon) {
  for (int y = horizon - 12; y < horizon; ++y) {
    const float t = static_cast<float>(horizon - 1 - y) / 11.0f;
    for (int x = 20; x < 120; ++x)
      for (int c = 0; c < 3; ++c) img->at(x, y, c) *= (0.9f - 0.6f * t) * ((x + y) % 3 == 0 ? 0.7f : 1.0f);
  }
}

// Pixels of the box [x0, x1) x [y0, y1) that the mask calls not sky.
long long NonSkyIn(const capture::SkyMask& m, int x0, int x1, int y0, int y1) {
  long long n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += m.sky[static_cast<size_t>(y) * m.width + x] < 0.5f;
  return n;
}

// With the default options none of the cloud's box [x0, x1, y0, y1) is called not sky and all
// of the building's is; the control options take more than `control_min` of the cloud's box
// for ground.
void ExpectCloudFloatsBuildingStands(const ImageRGB& img, const std::array<double, 3>& sun, const std::array<int, 4>& cloud,
                                     const std::array<int, 4>& building, const capture::SkyMaskOptions& control,
                                     long long control_min) {
  const capture::SkyMask m = capture::EstimateSkyMask(img, sun, {});
  EXPECT_EQ(NonSkyIn(m, cloud[0], cloud[1], cloud[2], cloud[3]), 0);
  EXPECT_EQ(NonSkyIn(m, building[0], building[1], building[2], building[3]),
            static_cast<long long>(building[1] - building[0]) * (building[3] - building[2]));
  const capture::SkyMask c = capture::EstimateSkyMask(img, sun, control);
  EXPECT_GT(NonSkyIn(c, cloud[0], cloud[1], cloud[2], cloud[3]), control_min);  // the control: grounded
}

void Paint(ImageRGB* img, int x0, int x1, int y0, int y1, float scale, bool texture) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) img->at(x, y, c) *= scale * (texture && ((x + y) % 3 == 0) ? 0.5f : 1.0f);
}

TEST(SkySegmentation, FindsTheBuildingAndKeepsTheFloatingCloud) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0);
  ImageRGB img = ClearSky(sun);
  const int h = img.height;
  const int horizon = HorizonRow(h);
  // A building 20 px wide from the horizon up ~17 deg (12 rows), 10x darker than the sky,
  // with window texture; a dark cloud blob 4x darker floating at ~45 deg, away from both.
  Paint(&img, 150, 170, horizon - 12, horizon, 0.1f, true);
  Paint(&img, 60, 80, 28, 36, 0.25f, false);
  const capture::SkyMask m = capture::EstimateSkyMask(img, sun, {});
  long long building = 0, cloud = 0, elsewhere = 0;
  for (int y = 0; y < horizon; ++y)
    for (int x = 0; x < img.width; ++x) {
      const bool ns = m.sky[static_cast<size_t>(y) * img.width + x] < 0.5f;
      if (x >= 150 && x < 170 && y >= horizon - 12) building += ns;
      else if (x >= 60 && x < 80 && y >= 28 && y < 36) cloud += ns;
      else elsewhere += ns;
    }
  // The building is 240 px: all of it, the cloud none of it (it floats), and outside both
  // at most the 1-px dilation ring around the building (2 x 12 + 20 + corners ~ 50 px).
  EXPECT_EQ(building, 240);
  EXPECT_EQ(cloud, 0);
  EXPECT_LE(elsewhere, 60);
  EXPECT_GT(m.floating_candidates, 100);  // the cloud was a candidate, dropped by the ground rule
  // Below the horizon: nothing is sky.
  for (int y = horizon; y < h; ++y)
    for (int x = 0; x < img.width; ++x) ASSERT_EQ(m.sky[static_cast<size_t>(y) * img.width + x], 0.0f);
  // Control: the clear sky alone has no non-sky above the horizon.
  const capture::SkyMask clear = capture::EstimateSkyMask(ClearSky(sun), sun, {});
  EXPECT_EQ(clear.non_sky_above_horizon, 0);
}

// A dark cloud mass standing on a bank of cumulus near the horizon floats: the bank's base is
// ~2.3 deg up where the game's draw distance puts it (1.5 km up, 35 km away), so the mass
// never reaches the ground band (1 deg: the lowest row above the horizon here, 0.7 deg). With
// the band at 4 deg the bank's lowest row (3.5 deg) grounded both: the control.
TEST(SkySegmentation, ADarkCloudMassOnACumulusBankFloats) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0);
  ImageRGB img = ClearSky(sun);
  const int h = img.height;
  const int horizon = HorizonRow(h);
  const double deg = 180.0 / M_PI;
  int base = horizon - 1;  // the lowest row at or above 2.3 deg
  while (latlong::Latitude(base, h) * deg < 2.3) --base;
  Paint(&img, 20, 120, base - 3, base + 1, 0.3f, true);  // the bank: 4 rows, textured
  Paint(&img, 40, 90, 30, base - 3, 0.25f, false);       // the mass above it, to ~40 deg
  Paint(&img, 150, 170, horizon - 12, horizon, 0.1f, true);  // a building, for the contrast
  capture::SkyMaskOptions four;
  four.ground_band_deg = 4.0;
  ExpectCloudFloatsBuildingStands(img, sun, {20, 120, 30, base + 1}, {150, 170, horizon - 12, horizon}, four, 1000);
}

// A grey cumulus bank drawn down to the horizon (the game's clouds reach it through the
// planet's curvature; so do a photo's over the sea or a plain) meets the ground band through
// haze: textured there, but hardly darker than the sky (none of it by the 0.7 of a dark
// candidate), so it floats; a building of the same height is dark where it stands. The
// control: with any contact grounding (ground_dark_share 0, the rule before) the bank is
// taken for ground.
TEST(SkySegmentation, ACloudBankFadingIntoTheHorizonHazeFloats) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0);
  ImageRGB img = ClearSky(sun);
  const int h = img.height;
  const int horizon = HorizonRow(h);
  PaintHazyBank(&img, horizon);
  Paint(&img, 150, 170, horizon - 12, horizon, 0.1f, true);  // the building
  capture::SkyMaskOptions any_contact;
  any_contact.ground_dark_share = 0.0;
  ExpectCloudFloatsBuildingStands(img, sun, {20, 120, horizon - 12, horizon}, {150, 170, horizon - 12, horizon},
                                  any_contact, 600);  // of the bank's 1200 px
}

// The same hazy bank with a narrow building standing against its right end: one component,
// whose contact with the ground band is mostly the bank's (not dark) and a tenth or less the
// building's (dark). The building's dark pixels on the band ground the component, and the
// building is found whole (the bank with it: one object to the rule).
TEST(SkySegmentation, ABuildingAgainstAHazyCloudBankStandsOnTheGround) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0);
  ImageRGB img = ClearSky(sun);
  const int horizon = HorizonRow(img.height);
  PaintHazyBank(&img, horizon);
  Paint(&img, 120, 130, horizon - 12, horizon, 0.1f, true);  // 10 px wide, touching the bank
  const capture::SkyMask m = capture::EstimateSkyMask(img, sun, {});
  EXPECT_EQ(NonSkyIn(m, 120, 130, horizon - 12, horizon), 120);
}

// Where segmentations fail: thin dark structures standing on the horizon (a pylon 2 px wide,
// a crane's 1-px mast and jib, a 1-px wire slung between the pylon and the mast) and a
// bright, colourless façade beside a bright sky (as bright as the sky next to it, grey where
// the sky is blue, flat: no window texture to give it away).
TEST(SkySegmentation, ThinStructuresAndABrightFacade) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0);
  ImageRGB img = ClearSky(sun);
  const int horizon = HorizonRow(img.height);
  std::vector<uint8_t> truth(img.pixels.size() / 3, 0);  // 1: a thin structure, 2: the façade
  auto dark = [&](int x, int y, uint8_t label) {
    for (int c = 0; c < 3; ++c) img.at(x, y, c) *= 0.15f;
    truth[static_cast<size_t>(y) * img.width + x] = label;
  };
  for (int y = horizon - 24; y < horizon; ++y) dark(40, y, 1), dark(41, y, 1);  // the pylon
  for (int y = horizon - 30; y < horizon; ++y) dark(100, y, 1);                 // the crane's mast
  for (int x = 88; x < 120; ++x) dark(x, horizon - 30, 1);                       // its jib
  for (int x = 42; x < 100; ++x) {                                               // the wire, sagging
    const double t = (x - 42) / 58.0;
    dark(x, horizon - 22 + static_cast<int>(std::lround(8.0 * t * (1.0 - t))), 1);  // 2 px of sag
  }
  for (int y = horizon - 14; y < horizon; ++y)  // the façade: the sky's luminance, grey
    for (int x = 180; x < 210; ++x) {
      const float Y = 0.2126f * img.at(x, y, 0) + 0.7152f * img.at(x, y, 1) + 0.0722f * img.at(x, y, 2);
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 1.1f * Y;
      truth[static_cast<size_t>(y) * img.width + x] = 2;
    }
  const capture::SkyMask m = capture::EstimateSkyMask(img, sun, {});
  long long n[3] = {0, 0, 0}, found[3] = {0, 0, 0};
  for (int y = 0; y < horizon; ++y)
    for (int x = 0; x < img.width; ++x) {
      const size_t i = static_cast<size_t>(y) * img.width + x;
      ++n[truth[i]];
      found[truth[i]] += m.sky[i] < 0.5f;
    }
  const double thin = static_cast<double>(found[1]) / n[1], facade = static_cast<double>(found[2]) / n[2];
  const double sky_lost = static_cast<double>(found[0]) / n[0];
  std::cout << "thin structures recall " << thin << " (" << n[1] << " px), facade recall " << facade << " (" << n[2]
            << " px), clear sky called non-sky " << sky_lost << "\n";
  // Every thin structure is found (the ground connection runs up the pylon and the mast and
  // along the wire), at the cost of the one-pixel ring around each (~2x their pixels).
  EXPECT_GE(thin, 0.95);
  EXPECT_LE(sky_lost, 0.03);
  // Known failure, pinned so that a change shows: a flat façade as bright as the sky is taken
  // for sky (its only cue is colour, and a grey cloud bank on the horizon has the same).
  EXPECT_LT(facade, 0.5);
}

// A wire too faint for the darkness and texture cues (one pixel at 0.8 of the sky: ln 0.22
// below it, against the darkness threshold of 0.7), slung from a pylon: found by its
// black-hat, hanging from the pylon. Beside it a fleecy cloud (its opacity rippling between 0
// and 1 every ~3 pixels, white over the blue sky) sits on a roof: its troughs are just as thin
// and dark, but the sky's blue shows in them (not neutral) and the cloud round them is
// textured: it stays sky. The control: line_darkness 0 leaves the wire in the sky.
TEST(SkySegmentation, AFaintWireHangsFromItsPylonAndACloudOnARoofStaysSky) {
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(60.0, 90.0);  // well away from the wire (~30 deg up)
  ImageRGB img = ClearSky(sun);
  const int horizon = HorizonRow(img.height);
  Paint(&img, 40, 42, horizon - 24, horizon, 0.15f, false);  // the pylon
  std::vector<std::pair<int, int>> wire;
  for (int x = 42; x < 140; ++x) {
    const double t = (x - 42) / 98.0;
    wire.emplace_back(x, horizon - 22 + static_cast<int>(std::lround(10.0 * t * (1.0 - t))));
  }
  for (const auto& [x, y] : wire)
    for (int c = 0; c < 3; ++c) img.at(x, y, c) *= 0.8f;
  Paint(&img, 170, 230, horizon - 6, horizon, 0.1f, false);  // the roof
  for (int y = horizon - 18; y < horizon - 6; ++y)             // the cloud on it
    for (int x = 170; x < 230; ++x) {
      const float a = 0.5f + 0.5f * static_cast<float>(std::sin(1.9 * x) * std::sin(2.3 * y));
      const float white = 1.5f * (0.2126f * img.at(x, y, 0) + 0.7152f * img.at(x, y, 1) + 0.0722f * img.at(x, y, 2));
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = a * white + (1.0f - a) * img.at(x, y, c);
    }
  auto wire_found = [&](const capture::SkyMask& m) {
    long long n = 0;
    for (const auto& [x, y] : wire) n += m.sky[static_cast<size_t>(y) * m.width + x] < 0.5f;
    return static_cast<double>(n) / wire.size();
  };
  const capture::SkyMask m = capture::EstimateSkyMask(img, sun, {});
  const long long cloud_taken = NonSkyIn(m, 170, 230, horizon - 18, horizon - 7);  // the roof's dilated ring left out
  std::cout << "faint wire found " << wire_found(m) << ", cloud pixels taken " << cloud_taken << " of 660\n";
  EXPECT_GE(wire_found(m), 0.95);
  EXPECT_LE(cloud_taken, 33);  // 5%
  capture::SkyMaskOptions off;
  off.line_darkness = 0.0;
  EXPECT_LE(wire_found(capture::EstimateSkyMask(img, sun, off)), 0.2);
}

TEST(SkySegmentation, OptionsNameTheField) {
  std::string why;
  capture::SkyMaskOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.darkness_quantile = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("darkness_quantile"), std::string::npos) << why;
  o = {};
  o.ground_dark_share = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("ground_dark_share"), std::string::npos) << why;
  o = {};
  o.line_darkness = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("line_darkness"), std::string::npos) << why;
  o = {};
  o.dilate_px = 99;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("dilate_px"), std::string::npos) << why;
  EXPECT_THROW(capture::EstimateSkyMask(ImageRGB(4, 2), std::nullopt, {}), Error);
}

// Floors: the measured numbers (bench/results/sky_segmentation.md: sunrise 0.98 / 0.70,
// sunset 1.00 / 0.79, the wires found) minus a margin of 0.05 for other OpenCV builds (grabCut's GMM fits
// can move a boundary by a pixel). Recall is bounded by the hand masks' conventions, not
// objects: the lowest 3.3 deg excluded wholesale and, at sunrise, a 260x80 px rectangle
// around the power lines (mostly sky between the wires).
struct HandMaskCase {
  const char* frame;
  const char* mask;
  double min_precision, min_recall;
};

TEST(SkySegmentation, PrecisionAndRecallAgainstTheHandMasks) {
  const HandMaskCase cases[] = {{"sunrise", "sunrise_mask.exr", 0.93, 0.65},
                                {"sunset", "sunset_mask.exr", 0.95, 0.74}};
  for (const auto& c : cases) {
    const std::string path = kRoot + "/datasets/real/" + c.frame + ".exr";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent: run datasets/fetch_real_skies.sh";
    const auto frame = capture::ReadLatLongFrame(path);
    const capture::SkyMask m = capture::EstimateSkyMask(frame.radiance, frame.sun_direction, {});
    int w = 0, h = 0;
    const auto ref = ReadExrChannel(kRoot + "/datasets/masks/" + c.mask, "R", &w, &h);
    const auto s = capture::ScoreNonSky(m, ref, w, h, 0.0);
    std::cout << "[sky mask] " << c.frame << ": precision " << s.precision << " recall " << s.recall << " IoU " << s.iou
              << "\n";
    EXPECT_GE(s.precision, c.min_precision) << c.frame;
    EXPECT_GE(s.recall, c.min_recall) << c.frame;
  }
}

#ifdef SKYCAL_BINARY
TEST(SkySegmentation, MaskVerbRefusesBadInputAndWritesNothing) {
  const auto dir = std::filesystem::temp_directory_path() / ("skycal-mask-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "m.exr").string();
  const std::string missing = (dir / "nope.exr").string();
  const std::string cmd = std::string(SKYCAL_BINARY) + " mask --reference " + missing + " --out " + out + " 2>" +
                          (dir / "err.txt").string();
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 1);
  EXPECT_FALSE(std::filesystem::exists(out));
  // Each out-of-range flag: exit 1, nothing written, the flag the user typed named with its
  // range (the library names SkyMaskOptions' fields).
  const auto refused = [&](const std::string& flag, const std::string& expected) {
    const std::string err = (dir / "err_flag.txt").string();
    const std::string c =
        std::string(SKYCAL_BINARY) + " mask --reference " + missing + " --out " + out + " " + flag + " 2>" + err;
    EXPECT_EQ(WEXITSTATUS(std::system(c.c_str())), 1) << flag;
    std::ifstream in(err);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find(expected), std::string::npos) << text;
    EXPECT_FALSE(std::filesystem::exists(out)) << flag;
  };
  refused("--horizon-deg 45", "--horizon-deg 45 (expected [-10, 30] deg)");
  refused("--ground-dark-share 2", "--ground-dark-share 2 (expected [0, 1])");
  std::filesystem::remove_all(dir);
}
#endif

}  // namespace
}  // namespace skycal
