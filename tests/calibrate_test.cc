// `skycal calibrate` (controllers/calibrate.h): its options, the sun wherever it is (the disc
// covered, the time and place), and the whole command on photos whose answer is known:
// files written, the game's image equal to `skycal render` of the calibrated preset, and
// every bad photo refused by name with nothing left behind.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "calibrate_plan.h"
#include "calibrate_sun.h"
#include "calibrate_weather.h"
#include "run_binary.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/capture/solar_position.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/capture/time_place.h"
#include "skycal/controllers/calibrate.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "test_util.h"

using skycal::testing::WriteText;

namespace skycal {
namespace {

const std::string kRoot = SKYCAL_SOURCE_DIR;
using controllers::CalibrateOptions;

double AngleDeg(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / kPi;
}

ImageRGB ModelSky(const std::array<double, 3>& sun, int w, int h, bool disc) {
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = w;
  req.height = h;
  req.sun_disc = disc;
  return render::CreateRenderer(render::Backend::kCpu)
      ->Render(render::LoadPreset(kRoot + "/datasets/presets/default_clear.json"), req);
}

TEST(Calibrate, OptionsNameTheFieldAndValue) {
  CalibrateOptions o;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "CalibrateOptions::photos is empty (expected at least one lat-long OpenEXR or Radiance picture, or a folder of them)");
  o.photos = {"a/sky.exr", "b/sky.exr"};
  o.out_dir = "out";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("two photos named 'sky'"), std::string::npos) << why;
  o.photos = {"a/sky.exr"};
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.latitude_deg = 95.0;
  o.longitude_deg = 10.0;
  o.time_iso8601 = "2026-06-21T12:00Z";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "CalibrateOptions::latitude_deg = 95 (expected [-90, 90] degrees)");
  o.latitude_deg = 45.0;
  o.time_iso8601.reset();
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("latitude_deg given without time_iso8601"), std::string::npos) << why;
  o.latitude_deg = 45.0;
  o.time_iso8601 = "2026-06-21 noon";  // refused up front, not when a sun is first asked of the time
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("CalibrateOptions::time_iso8601"), std::string::npos) << why;
  o = {};
  o.photos = {"sky.exr"};
  o.out_dir = "out";
  o.sun_elevation_deg = 10.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("sun_elevation_deg and sun_azimuth_deg"), std::string::npos) << why;
}

// The sun of a real clear photo with its disc covered (every pixel within 5 deg of the
// sun set to the median of the ring 5-8 deg): found from the sky's pattern, within its
// stated uncertainty and a few degrees.
TEST(Calibrate, TheSunWithItsDiscCoveredIsFoundFromTheSky) {
  const std::string path = kRoot + "/datasets/real/sunrise.exr";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent: run datasets/fetch_real_skies.sh";
  capture::LatLongFrame f = capture::ReadLatLongFrame(path);
  ASSERT_TRUE(f.sun_direction.has_value());
  const std::array<double, 3> truth = *f.sun_direction;
  ImageRGB& img = f.radiance;
  std::vector<float> ring[3];
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double a = AngleDeg(latlong::PixelDirection(x, y, img.width, img.height), truth);
      if (a >= 5.0 && a < 8.0)
        for (int c = 0; c < 3; ++c) ring[c].push_back(img.at(x, y, c));
    }
  ASSERT_GT(ring[0].size(), 10u);
  float median[3];
  for (int c = 0; c < 3; ++c) {
    std::nth_element(ring[c].begin(), ring[c].begin() + ring[c].size() / 2, ring[c].end());
    median[c] = ring[c][ring[c].size() / 2];
  }
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (AngleDeg(latlong::PixelDirection(x, y, img.width, img.height), truth) < 5.0)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = median[c];
  const capture::SkyMask mask = capture::EstimateSkyMask(img, std::nullopt, {});
  CalibrateOptions o;
  const controllers::PhotoSun s = controllers::ChoosePhotoSun(img, mask.sky, std::nullopt, o);
  ASSERT_TRUE(s.direction.has_value()) << s.refusal;
  EXPECT_EQ(s.source, "sky");
  ASSERT_TRUE(s.uncertainty_deg.has_value());
  const double error = AngleDeg(*s.direction, truth);
  std::cout << "[calibrate] sunrise, disc covered: sun found " << error << " deg off, uncertainty " << *s.uncertainty_deg
            << " deg\n";
  EXPECT_LT(error, 5.0);
  EXPECT_LE(error, *s.uncertainty_deg + 1.0);
}

// An overcast deck whose sun nothing places: the nominal sun sits on the deck's bright patch
// within 1.5 deg (the gradient under the patch lifts the smoothed peak by about a degree), not
// at the centre of a 10-degree cell (5.1 deg off here), and across the lat-long's seam too (the
// smoothing wraps). The deck: the CIE overcast gradient (1 + 2 sin el) / 3, a patch of 8 deg
// round a sun between cell centres, a texture of +-10% and a tower masked out. A control: with
// the patch off, the peak is the gradient's, at the zenith side of the frame, far from the sun.
TEST(Calibrate, TheNominalSunOfAnOvercastDeckSitsOnItsBrightPatch) {
  const int w = 512, h = 256;
  auto deck = [&](const std::array<double, 3>& sun, double patch) {
    ImageRGB img(w, h);
    std::vector<float> sky(static_cast<size_t>(w) * h, 1.0f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const auto d = latlong::PixelDirection(x, y, w, h);
        const double el = latlong::ElevationDeg(d), g = AngleDeg(d, sun);
        const double texture = 1.0 + 0.1 * std::sin(0.9 * x) * std::cos(1.3 * y);
        const double L = ((1.0 + 2.0 * std::sin(std::max(el, 0.0) * kPi / 180.0)) / 3.0 +
                          patch * std::exp(-0.5 * (g / 8.0) * (g / 8.0))) * texture;
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(L);
        if (std::abs(x - 300) < 12 && el < 30.0) sky[static_cast<size_t>(y) * w + x] = 0.0f;  // a tower
      }
    return controllers::NominalOvercastSun(img, sky);
  };
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(21.0, 41.5);  // 10-deg cells: (25, 45), 5 deg off
  const auto s = deck(sun, 1.0);
  ASSERT_TRUE(s && s->direction);
  std::cout << "[calibrate] overcast deck: the nominal sun " << AngleDeg(*s->direction, sun) << " deg off its patch (el "
            << latlong::ElevationDeg(*s->direction) << ", az " << latlong::AzimuthDeg(*s->direction) << ")\n";
  EXPECT_LT(AngleDeg(*s->direction, sun), 1.5);
  EXPECT_EQ(s->uncertainty_deg, 90.0);
  const auto seam_sun = latlong::DirectionFromElevationAzimuthDeg(21.0, 178.0);  // 2 deg from the seam
  const auto seam = deck(seam_sun, 1.0);
  ASSERT_TRUE(seam && seam->direction);
  EXPECT_LT(AngleDeg(*seam->direction, seam_sun), 1.5);
  const auto flat = deck(sun, 0.0);
  ASSERT_TRUE(flat && flat->direction);
  EXPECT_GT(AngleDeg(*flat->direction, sun), 30.0);
  EXPECT_THROW(capture::BrightestSkyPatch(ImageRGB(w, h), std::vector<float>(10, 1.0f), 5.0, 5.0), Error);
}

// The time and place: with north known, the SPA's direction exactly; without it, the SPA's
// elevation with the sky's azimuth.
TEST(Calibrate, TheSunOfATimeAndPlace) {
  capture::SpaInput in = capture::ParseIso8601("2026-06-21T17:30:00+02:00");
  in.latitude_deg = 48.2;
  in.longitude_deg = 16.4;
  const capture::SpaResult spa = capture::ComputeSolarPosition(in);
  const std::array<double, 3> truth = capture::SunDirectionInFrame(spa, 30.0);
  const ImageRGB sky = ModelSky(truth, 256, 128, false);
  const std::vector<float> all(static_cast<size_t>(256) * 128, 1.0f);
  CalibrateOptions o;
  o.time_iso8601 = "2026-06-21T17:30:00+02:00";
  o.latitude_deg = 48.2;
  o.longitude_deg = 16.4;
  o.north_longitude_deg = 30.0;
  controllers::PhotoSun s = controllers::ChoosePhotoSun(sky, all, std::nullopt, o);
  ASSERT_TRUE(s.direction.has_value()) << s.refusal;
  EXPECT_EQ(s.source, "time and place");
  EXPECT_LT(AngleDeg(*s.direction, truth), 1e-9);
  o.north_longitude_deg.reset();
  s = controllers::ChoosePhotoSun(sky, all, std::nullopt, o);
  ASSERT_TRUE(s.direction.has_value()) << s.refusal;
  EXPECT_EQ(s.source, "time and place, azimuth from the sky");
  EXPECT_NEAR(latlong::ElevationDeg(*s.direction), spa.elevation_deg, 1e-9);
  EXPECT_LT(AngleDeg(*s.direction, truth), 3.0);
  o.time_iso8601 = "2026-06-21 noon";
  EXPECT_THROW(controllers::ChoosePhotoSun(sky, all, std::nullopt, o), Error);
}

// A photo that says when and where it was taken (OpenEXR's standard capDate, utcOffset,
// latitude, longitude, as `capture` writes them from the brackets' EXIF): its hidden sun's
// elevation is the time and place's; without the attributes the sky alone places it.
TEST(Calibrate, TheSunOfTheFilesOwnTimeAndPlace) {
  capture::SpaInput in = capture::ParseIso8601("2026-06-21T17:30:00+02:00");
  in.latitude_deg = 48.25;
  in.longitude_deg = 16.5;
  const capture::SpaResult spa = capture::ComputeSolarPosition(in);
  const std::array<double, 3> truth = capture::SunDirectionInFrame(spa, 30.0);
  testing::ScratchDir dir("calibrate-file-time");
  capture::LatLongFrame f;
  f.radiance = ModelSky(truth, 256, 128, false);
  f.extra.strings["capDate"] = "2026:06:21 17:30:00";
  f.extra.floats["utcOffset"] = -7200.0f;  // UTC = local + utcOffset
  f.extra.floats["latitude"] = 48.25f;
  f.extra.floats["longitude"] = 16.5f;
  capture::WriteLatLongFrame(dir / "timed.exr", f);
  const controllers::PhotoAnalysis a = controllers::AnalysePhoto(dir / "timed.exr", CalibrateOptions{});
  ASSERT_TRUE(a.sun.direction.has_value()) << a.sun.refusal;
  EXPECT_EQ(a.sun.source, "time and place, azimuth from the sky (the file's EXR capDate + utcOffset)");
  EXPECT_NEAR(latlong::ElevationDeg(*a.sun.direction), spa.elevation_deg, 1e-6);
  EXPECT_LT(AngleDeg(*a.sun.direction, truth), 3.0);
  ASSERT_TRUE(a.time_iso8601.has_value());
  EXPECT_EQ(*a.time_iso8601, "2026-06-21T17:30:00+02:00");
  // Control: the same pixels without the attributes.
  f.extra = {};
  capture::WriteLatLongFrame(dir / "untimed.exr", f);
  const controllers::PhotoAnalysis u = controllers::AnalysePhoto(dir / "untimed.exr", CalibrateOptions{});
  EXPECT_EQ(u.sun.source, "sky");
  EXPECT_FALSE(u.time_iso8601.has_value());
}

#ifdef SKYCAL_BINARY
testing::ProcessResult Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

// `skycal calibrate` on one photo into `out` with `flags` only, without the report and the
// game tables (what these tests judge is the photo's own outputs).
testing::ProcessResult CalibrateQuietly(const std::string& photo, const std::string& out, const std::string& flags = "") {
  return Skycal("calibrate --photo " + photo + " --out " + out + flags + " --no-report --no-export");
}

// A photo in the project's convention (envmap=latlong), as a camera rig or `import` writes it.
void WritePhoto(const std::string& path, const ImageRGB& img) {
  capture::LatLongFrame f;
  f.radiance = img;
  capture::WriteLatLongFrame(path, f);
}

// A clear sky whose answer is known (the model's own, sun at 30 deg, disc drawn): calibrated
// with no flag; every file there; the kind, the sun and a small error of the game's image;
// render.exr equal to `skycal render` of the calibrated preset times the fit's exposure.
TEST(Calibrate, AClearSkyThroughTheBinary) {
  testing::ScratchDir s("calibrate-clear");
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0);
  ImageRGB img = ModelSky(sun, 512, 256, true);  // at 256 x 128 the point-sampled disc (0.53 deg) falls between pixels
  for (float& v : img.pixels) v *= 0.01f;  // a camera's units, not the model's
  WritePhoto(s / "park.exr", img);
  const auto r = Skycal("calibrate --photo " + s / "park.exr" + " --out " + s / "out" + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["calibrated"], 1);
  const std::string dir = s / "out/park";
  for (const char* f : {"photo.exr", "mask.exr", "preset.json", "fit.json", "render.exr", "compare.png", "report.html"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  EXPECT_TRUE(std::filesystem::exists(s / "out/game/manifest.json"));
  EXPECT_TRUE(std::filesystem::exists(s / "out/report.html"));
  const fit::FitResultFile f = fit::ReadFitResultFile(dir + "/fit.json");
  ASSERT_TRUE(f.calibration.has_value());
  EXPECT_EQ(f.calibration->sky_kind, "clear");
  EXPECT_EQ(f.calibration->sun_source, "disc");
  EXPECT_LT(f.calibration->game_per_pixel_log_rmse, 0.05);
  EXPECT_LT(f.calibration->game_appearance_error, 0.03);
  EXPECT_LT(AngleDeg(f.references.at(0).sun_direction, sun), 1.0);
  // The game's image is `skycal render` of the preset at that sun and size, times the exposure.
  const auto& d = f.references.at(0).sun_direction;
  const auto rr = Skycal("render --preset " + dir + "/preset.json --sun-dir " + std::to_string(d[0]) + "," +
                         std::to_string(d[1]) + "," + std::to_string(d[2]) + " --size 512x256 --out " + s / "r.exr");
  ASSERT_EQ(rr.rc, 0) << rr.err;
  const ImageRGB game = ReadExrRGB(dir + "/render.exr").image;
  const ImageRGB plain = ReadExrRGB(s / "r.exr").image;
  ASSERT_EQ(game.pixels.size(), plain.pixels.size());
  double worst = 0.0;
  for (size_t i = 0; i < game.pixels.size(); ++i) {
    const double want = plain.pixels[i] * f.references[0].exposure;
    worst = std::max(worst, std::abs(game.pixels[i] - want) / std::max(want, 1e-12));
  }
  EXPECT_LT(worst, 1e-4);  // the --sun-dir text rounds the direction to 6 digits
  // fit.json's two numbers are `skycal compare` of the files beside it, the disc's cone left out.
  EXPECT_EQ(f.calibration->game_sun_cone_deg, 3.0);  // the fit's sun cone: the disc is drawn
  const std::string files = " --photo " + dir + "/photo.exr --game " + dir + "/render.exr --mask " + dir + "/mask.exr";
  const auto same = Skycal("compare" + files + " --sun-cone 3 --json");
  ASSERT_EQ(same.rc, 0) << same.err;
  const auto c = nlohmann::json::parse(same.out);
  EXPECT_NEAR(c["per_pixel_log_rmse"].get<double>(), f.calibration->game_per_pixel_log_rmse, 1e-12);
  EXPECT_NEAR(c["appearance_error"].get<double>(), f.calibration->game_appearance_error, 1e-12);
  EXPECT_EQ(c["sky_pixels"].get<int>(), f.calibration->game_sky_pixels);
  // The control: with the disc's pixels in, other numbers.
  const auto disc = nlohmann::json::parse(Skycal("compare" + files + " --json").out);
  EXPECT_GT(disc["sky_pixels"].get<int>(), f.calibration->game_sky_pixels);

  // A second photo into the same DIR: the first calibration stays, the game tables hold both;
  // a photo that cannot be calibrated beside it loses nothing of either.
  WritePhoto(s / "field.exr", img);
  ImageRGB black(512, 256);
  WritePhoto(s / "black.exr", black);
  const auto again = Skycal("calibrate --photo " + s / "field.exr" + " --photo " + s / "black.exr" + " --out " +
                            s / "out" + " --json --no-report");
  EXPECT_EQ(again.rc, 1) << again.err;  // black.exr refused
  EXPECT_TRUE(std::filesystem::exists(dir + "/render.exr"));
  EXPECT_TRUE(std::filesystem::exists(s / "out/field/render.exr"));
  EXPECT_FALSE(std::filesystem::exists(s / "out/black"));
  const auto manifest = nlohmann::json::parse(testing::Slurp(s / "out/game/manifest.json"));
  EXPECT_EQ(manifest["presets"].size(), 2u) << manifest.dump();
}

// A folder given as --photo stands for its pictures, by their first bytes and in name order;
// its other files are named as left out, hidden ones skipped; a folder with no picture is
// refused by name with nothing written.
TEST(Calibrate, AFolderOfPhotosIsItsPictures) {
  testing::ScratchDir s("calibrate-folder");
  std::filesystem::create_directories(s / "shoot");
  ImageRGB img = ModelSky(latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0), 512, 256, true);
  WritePhoto(s / "shoot/b_park.exr", img);
  WritePhoto(s / "shoot/a_field.exr", img);
  WritePhoto(s / "shoot/.hidden.exr", img);
  WriteText(s / "shoot/notes.txt", "shot at noon");
  const auto r = CalibrateQuietly(s / "shoot/", s / "out", " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["photos"].size(), 2u) << r.out;
  EXPECT_EQ(j["photos"][0]["photo"], s / "shoot/a_field.exr");
  EXPECT_EQ(j["photos"][1]["photo"], s / "shoot/b_park.exr");
  EXPECT_NE(r.err.find("left out, not OpenEXR or Radiance pictures: " + s / "shoot/notes.txt"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(s / "out/.hidden"));
  std::filesystem::create_directories(s / "empty");
  WriteText(s / "empty/readme.txt", "nothing here");
  const auto e = Skycal("calibrate --photo " + s / "empty" + " --out " + s / "out2");
  EXPECT_EQ(e.rc, 1);
  EXPECT_NE(e.err.find(s / "empty" + ": no OpenEXR or Radiance picture in the folder (1 other file(s))"), std::string::npos)
      << e.err;
  EXPECT_FALSE(std::filesystem::exists(s / "out2"));
}

// Every image a fit record names (a relative *.png or *.exr under "images") exists beside it;
// returns how many it names.
int ExpectNamedImagesExist(const std::filesystem::path& record) {
  int named = 0;
  std::function<void(const nlohmann::json&, bool)> walk = [&](const nlohmann::json& j, bool images) {
    if (j.is_object()) {
      for (auto it = j.begin(); it != j.end(); ++it) walk(it.value(), images || it.key() == "images");
    } else if (j.is_array()) {
      for (const auto& v : j) walk(v, images);
    } else if (images && j.is_string()) {
      ++named;
      EXPECT_TRUE(std::filesystem::exists(record.parent_path() / j.get<std::string>()))
          << record << " names " << j.get<std::string>() << ", which is not there";
    }
  };
  walk(ReadJsonFile(record.string()), false);
  return named;
}

// The refit's free parameters at an end of their range are named in its decision (in
// CloudLightingNames order), the held ones and those inside their range are not; its restarts
// from the far side of a bound, and the holds it released, are said.
TEST(Calibrate, TheRefitNamesTheParametersItLeftAtTheEndOfTheirRangeAndItsRestarts) {
  const nlohmann::json clouds = {{"parameters",
                                  {{"ms_a", {{"value", 0.0}, {"held", false}}},
                                   {"phase_g1", {{"value", 0.99}, {"held", false}}},
                                   {"sun_scale", {{"value", 1.2}, {"held", false}}},
                                   {"phase_g2", {{"value", 0.99}, {"held", true}}}}}};
  EXPECT_EQ(controllers::ParametersAtBounds(clouds), "phase_g1 0.99 (its maximum), ms_a 0 (its minimum)");
  EXPECT_EQ(controllers::ParametersAtBounds({{"parameters", nlohmann::json::object()}}), "");
  EXPECT_EQ(controllers::ParametersAtBounds(nlohmann::json()), "");
  // The restarts from the far side of a bound, as the refit's record gives them.
  EXPECT_EQ(controllers::BoundRestartsText({{"solve", {{"bound_restarts", {{"tried", 2}, {"kept", "ms_a"}}}}}}),
            "; solved again from the far side of a bound 2 time(s), the restart in ms_a kept (lower cost)");
  EXPECT_EQ(controllers::BoundRestartsText({{"solve", {{"bound_restarts", {{"tried", 1}, {"kept", ""}}}}}}),
            "; solved again from the far side of a bound 1 time(s), the first solve kept (lower cost)");
  EXPECT_EQ(controllers::BoundRestartsText({{"solve", {{"iterations", 10}}}}), "");
  EXPECT_EQ(controllers::BoundRestartsText(nlohmann::json()), "");
  // The holds released after the solve, kept or not.
  const nlohmann::json released = {{"freed", {"phase_blend", "ms_b"}}, {"kept", true}, {"cost_before", 0.10051},
                                   {"cost_after", 0.09479}};
  EXPECT_EQ(controllers::ReleasedHoldsText({{"solve", {{"released_holds", released}}}}),
            "; then the holds of the separability rule released (phase_blend, ms_b) and the solve continued: cost "
            "0.1005 -> 0.0948, kept (the freed values are the image's best, not determined ones)");
  nlohmann::json higher = released;
  higher["kept"] = false;
  higher["cost_after"] = 0.2;
  EXPECT_EQ(controllers::ReleasedHoldsText({{"solve", {{"released_holds", higher}}}}),
            "; then the holds of the separability rule released (phase_blend, ms_b) and the solve continued: cost "
            "0.1005 -> 0.2, not kept (no lower)");
  EXPECT_EQ(controllers::ReleasedHoldsText({{"solve", {{"iterations", 10}}}}), "");
}

// Every file a record names as read (a reference's path, a mask, the starting preset; relative:
// beside the record) is where the record says once calibrate has committed (the fits read them
// from its staging directory, gone by then), or the record says it was an intermediate not kept;
// returns how many.
int ExpectRecordedPathsResolve(const std::filesystem::path& record) {
  int named = 0;
  std::function<void(const nlohmann::json&, bool)> walk = [&](const nlohmann::json& j, bool path) {
    if (j.is_object()) {
      for (auto it = j.begin(); it != j.end(); ++it)
        walk(it.value(), it.key() == "path" || it.key() == "mask" || it.key() == "masks" || it.key() == "cloud_preset");
    } else if (j.is_array()) {
      for (const auto& v : j) walk(v, path);
    } else if (path && j.is_string()) {
      const std::string p = j.get<std::string>();
      if (p.empty()) return;  // none given
      ++named;
      EXPECT_EQ(p.find(".tmp-"), std::string::npos) << record << " names the staging path " << p;
      const std::filesystem::path at =
          std::filesystem::path(p).is_absolute() ? std::filesystem::path(p) : record.parent_path() / p;
      EXPECT_TRUE(std::filesystem::exists(at) || p.ends_with("(an intermediate of the refit, not kept)"))
          << record << " names " << p << ", which is not there";
    }
  };
  walk(ReadJsonFile(record.string()), false);
  return named;
}

// A partly cloudy sky whose clouds are known (the game's own march over a procedural weather
// map): with the weather map inverted from the photo and the lighting refitted on it, the
// game's image is nearer the photo than with the statistics fit's map and lighting, and each
// refinement render brings the rendered cloud opacity nearer the photo's.
TEST(Calibrate, APartlyCloudySkyGetsItsCloudsWhereThePhotoHasThem) {
  testing::ScratchDir s("calibrate-cloudy");
  ASSERT_EQ(Skycal("weather --seed 5 --size 256 --mean-coverage 0.25 --coverage-contrast 3 --coverage-cells 8 "
                   "--mean-precipitation 0 --out " + s / "w.exr").rc, 0);
  const auto rr = Skycal("render --preset " + kRoot + "/datasets/presets/default_cloudy.json --clouds --weather-map " +
                         s / "w.exr" + " --sun-elevation 40 --sun-azimuth 60 --size 512x256 --out " + s / "scattered.exr");
  ASSERT_EQ(rr.rc, 0) << rr.err;
  const auto a = CalibrateQuietly(s / "scattered.exr", s / "inverted");
  ASSERT_EQ(a.rc, 0) << a.err;
  const auto b = CalibrateQuietly(s / "scattered.exr", s / "statistical", " --no-weather-inversion");
  ASSERT_EQ(b.rc, 0) << b.err;
  const fit::FitResultFile inv = fit::ReadFitResultFile(s / "inverted/scattered/fit.json");
  const fit::FitResultFile stat = fit::ReadFitResultFile(s / "statistical/scattered/fit.json");
  ASSERT_TRUE(inv.calibration && stat.calibration);
  EXPECT_EQ(inv.calibration->sky_kind, "partly cloudy");
  std::cout << "[calibrate] scattered cumulus: per-pixel " << stat.calibration->game_per_pixel_log_rmse << " -> "
            << inv.calibration->game_per_pixel_log_rmse << ", appearance " << stat.calibration->game_appearance_error
            << " -> " << inv.calibration->game_appearance_error << "\n";
  EXPECT_LT(inv.calibration->game_appearance_error, 0.8 * stat.calibration->game_appearance_error);
  // The sun (40 deg up, azimuth 60) is behind the dark mass in the photo; the game's clouds
  // hide it too: within 3 degrees of it the game is no brighter than the photo (measured 0.011
  // of it; the glare once carved a hole there through which the game drew the disc: 4.9x).
  {
    const ImageRGB photo = ReadExrRGB(s / "inverted/scattered/photo.exr").image;
    const ImageRGB game = ReadExrRGB(s / "inverted/scattered/render.exr").image;
    const auto sun = latlong::DirectionFromElevationAzimuthDeg(40.0, 60.0);
    double p = 0.0, g = 0.0;
    for (int y = 0; y < game.height; ++y)
      for (int x = 0; x < game.width; ++x) {
        const auto d = latlong::PixelDirection(x, y, game.width, game.height);
        if (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] < std::cos(3.0 * kPi / 180.0)) continue;
        for (int c = 0; c < 3; ++c) p += photo.at(x, y, c), g += game.at(x, y, c);
      }
    ASSERT_GT(p, 0.0);
    std::cout << "[calibrate] toward the hidden sun, game / photo: " << g / p << "\n";
    EXPECT_LT(g / p, 1.0);
  }
  EXPECT_LT(inv.calibration->game_per_pixel_log_rmse, 0.8 * stat.calibration->game_per_pixel_log_rmse);
  // The decision's opacity RMS per render falls: by a quarter over the renders, and no render
  // more than the decision's rounding (0.001) above the one before (it flattens near the end).
  std::vector<double> rms;
  for (const fit::FitDecision& d : inv.decisions)
    if (d.what.starts_with("weather map inverted")) {
      std::istringstream in(d.why.substr(d.why.find("opacity RMS") + 11));
      double v;
      while (in >> v) rms.push_back(v);
    }
  ASSERT_GE(rms.size(), 2u);
  for (size_t i = 1; i < rms.size(); ++i) EXPECT_LE(rms[i], rms[i - 1] + 0.0015) << i;
  EXPECT_LT(rms.back(), 0.75 * rms.front());
  // Which texels the photo constrained: the map beside the preset, as many as the decision says.
  int constrained = -1, texels = -1;
  for (const fit::FitDecision& d : inv.decisions)
    if (d.what.starts_with("weather map inverted")) std::istringstream(d.why) >> constrained;
  for (const fit::FitDecision& d : inv.decisions)
    if (d.what.starts_with("weather map inverted")) texels = std::stoi(d.why.substr(d.why.find(" of ") + 4));
  const ImageRGB seen = ReadExrRGB(s / "inverted/scattered/weather_constrained.exr").image;
  EXPECT_EQ(seen.width * seen.height, texels);
  EXPECT_EQ(ReadExrRGB(s / "inverted/scattered/preset.weather.exr").image.width, seen.width);
  int ones = 0;
  for (size_t i = 0; i < seen.pixels.size(); i += 3) ones += seen.pixels[i] > 0.5f;
  EXPECT_EQ(ones, constrained);
  EXPECT_GT(constrained, 0);
  EXPECT_LT(constrained, texels);
  // Then the lighting refitted on those shapes, precipitation read from the light where the
  // photo's clouds are darker, and the lighting refitted again: three decisions in that order,
  // and the statistics fit's record kept.
  std::vector<std::string> lit;
  for (const fit::FitDecision& d : inv.decisions)
    if (d.what.starts_with("cloud lighting refitted") || d.what.starts_with("precipitation where")) lit.push_back(d.what);
  ASSERT_EQ(lit.size(), 3u);
  EXPECT_EQ(lit[0], "cloud lighting refitted pixel by pixel on the recovered shapes (known shapes)");
  EXPECT_TRUE(lit[1].starts_with("precipitation where"));
  EXPECT_EQ(lit[2], "cloud lighting refitted again with the precipitation (known shapes)");
  // The clear sky near the horizon is said to be fitted between clouds, with the share of
  // the sky below 20 deg that is cloud in the photo (at least the tenth that makes it said).
  int horizon_cloud_percent = -1;
  for (const fit::FitDecision& d : inv.decisions)
    if (d.what == "the clear sky below 20 deg fitted between the photo's clouds") horizon_cloud_percent = std::stoi(d.why);
  EXPECT_GE(horizon_cloud_percent, 10);
  EXPECT_LE(horizon_cloud_percent, 100);
  {
    const ImageRGB weather = ReadExrRGB(s / "inverted/scattered/preset.weather.exr").image;
    double rain = 0.0;
    for (size_t i = 1; i < weather.pixels.size(); i += 3) rain += weather.pixels[i];
    EXPECT_GT(rain, 0.0);  // the truth has none; the light asked for it where the shapes are too bright
  }
  EXPECT_TRUE(std::filesystem::exists(s / "inverted/scattered/fit.statistics.json"));
  // The statistics only start the refit on the placed clouds: one render per weather map
  // there, two where they are the calibration's clouds (--no-weather-inversion).
  const auto renders_and_maps = [](const std::string& file) {
    const nlohmann::json j = ReadJsonFile(file).at("cloud_stats");
    return std::pair{j.at("renders_per_evaluation").get<int>(), j.at("weather_maps").get<int>()};
  };
  const auto [inv_renders, inv_maps] = renders_and_maps(s / "inverted/scattered/fit.statistics.json");
  const auto [stat_renders, stat_maps] = renders_and_maps(s / "statistical/scattered/fit.json");
  EXPECT_EQ(inv_renders, inv_maps);
  EXPECT_EQ(stat_renders, 2 * stat_maps);
  // The records name only images that are there: the refit's previews in fit.json; the
  // statistics fit, whose outputs the refit replaces, drew none (it used to name six, three of
  // them deleted with its fit/ and three the refit's under its names).
  EXPECT_EQ(ExpectNamedImagesExist(s / "inverted/scattered/fit.json"), 3);
  EXPECT_EQ(ExpectNamedImagesExist(s / "inverted/scattered/fit.statistics.json"), 0);
  EXPECT_FALSE(std::filesystem::exists(s / "inverted/scattered/refit"));
  // The records name the committed photo and mask (and the refit's starting preset as not kept).
  EXPECT_EQ(ExpectRecordedPathsResolve(s / "inverted/scattered/fit.json"), 4);
  EXPECT_EQ(ExpectRecordedPathsResolve(s / "inverted/scattered/fit.statistics.json"), 2);
  EXPECT_EQ(ExpectRecordedPathsResolve(s / "inverted/scattered/preset.json"), 4);
  EXPECT_FALSE(std::filesystem::exists(s / "inverted/scattered/inverted_shapes"));

  // The true map given and held: the preset carries it texel for texel, nothing is inverted,
  // and the game's image is nearer the photo than with the inverted shapes (the shapes are
  // the photo's own: what is left is the lighting fit's).
  const auto held = CalibrateQuietly(s / "scattered.exr", s / "held", " --weather-map " + s / "w.exr");
  ASSERT_EQ(held.rc, 0) << held.err;
  const ImageRGB given = ReadExrRGB(s / "w.exr").image, kept = ReadExrRGB(s / "held/scattered/preset.weather.exr").image;
  EXPECT_EQ(given.pixels, kept.pixels);
  EXPECT_FALSE(std::filesystem::exists(s / "held/scattered/weather_constrained.exr"));
  const fit::FitResultFile h = fit::ReadFitResultFile(s / "held/scattered/fit.json");
  bool said = false;
  for (const fit::FitDecision& d : h.decisions) said |= d.what == "weather map: the user's, held (not inverted)";
  EXPECT_TRUE(said);
  std::cout << "[calibrate] the true map held: per-pixel " << h.calibration->game_per_pixel_log_rmse << ", appearance "
            << h.calibration->game_appearance_error << "\n";
  EXPECT_LT(h.calibration->game_per_pixel_log_rmse, inv.calibration->game_per_pixel_log_rmse);
  // On the photo's own shapes the game's image is the photo: the re-render target of the
  // weather-map issue (0.05). Measured 0.037 / 0.026 with the sky stage on the photo's surely
  // clear pixels (the colour ramp without its allowance by the sun; 0.034 / 0.015 with it, and
  // 0.079 / 0.039 with the sun's 20 degrees left out); 0.199 / 0.127 when it fitted the pixels
  // clear through the shapes (none in the LUT columns 2-6 degrees up, extrapolated 15x too
  // bright behind the clouds).
  EXPECT_LT(h.calibration->game_per_pixel_log_rmse, 0.05);
  EXPECT_LT(h.calibration->game_appearance_error, 0.03);
  // The multiple scattering is recovered (default_cloudy's ms_a 0.5; measured 0.508). The sun
  // scale and the ambient are not asserted: they trade with the fitted atmosphere's sun and
  // sky irradiance at the clouds (1.59 and 1.15 here, where the image matches to 3%).
  const nlohmann::json c = ReadJsonFile(s / "held/scattered/preset.json").at("clouds");
  EXPECT_NEAR(c.at("ms_a").at("value").get<double>(), 0.5, 0.03);
  // A map that is not there: exit 1, named, nothing written.
  const auto missing = Skycal("calibrate --photo " + s / "scattered.exr" + " --out " + s / "none --weather-map " +
                              s / "nope.exr");
  EXPECT_EQ(missing.rc, 1);
  EXPECT_NE(missing.err.find("nope.exr"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(s / "none"));
}

// A partly cloudy photo wider than the inversion's renders (1024x512): the refit reads it
// box-averaged to 512 (its lighting and LUT need no more pixels; at 2048x1024 the full-size
// refit was most of the command), while the game's image is rendered and judged at the photo's
// own size, about as near the photo as the same sky's at 512; and one of a size that divides
// into none of the working widths (600x300).
TEST(Calibrate, AWidePhotoIsRefittedAtTheInversionsWidthAndJudgedAtItsOwn) {
  testing::ScratchDir s("calibrate-wide");
  ASSERT_EQ(Skycal("weather --seed 5 --size 256 --mean-coverage 0.25 --coverage-contrast 3 --coverage-cells 8 "
                   "--mean-precipitation 0 --out " + s / "w.exr").rc, 0);
  for (const char* size : {"512x256", "1024x512", "600x300"}) {
    const auto rr = Skycal("render --preset " + kRoot + "/datasets/presets/default_cloudy.json --clouds --weather-map " +
                           s / "w.exr" + " --sun-elevation 40 --sun-azimuth 60 --size " + size + " --out " + s / (std::string("p") + size + ".exr"));
    ASSERT_EQ(rr.rc, 0) << rr.err;
    const auto c = CalibrateQuietly(s / (std::string("p") + size + ".exr"), s / "out");
    ASSERT_EQ(c.rc, 0) << c.err;
  }
  const fit::FitResultFile narrow = fit::ReadFitResultFile(s / "out/p512x256/fit.json");
  const fit::FitResultFile wide = fit::ReadFitResultFile(s / "out/p1024x512/fit.json");
  ASSERT_TRUE(narrow.calibration && wide.calibration);
  bool refitted = false;
  for (const fit::FitDecision& d : wide.decisions) refitted |= d.what.starts_with("cloud lighting refitted");
  EXPECT_TRUE(refitted);
  EXPECT_EQ(ReadExrRGB(s / "out/p1024x512/render.exr").image.width, 1024);
  EXPECT_EQ(ReadExrRGB(s / "out/p1024x512/fit/photo.exr").image.width, 512);  // the refit's own image
  EXPECT_EQ(ReadExrRGB(s / "out/p1024x512/fit/photo.exr").attributes.strings.at("skycalReference"),
            "refit_inputs/photo.exr (an intermediate of the refit, not kept)");
  EXPECT_EQ(ExpectRecordedPathsResolve(s / "out/p1024x512/fit.json"), 4);
  std::cout << "[calibrate] 512 wide: per-pixel " << narrow.calibration->game_per_pixel_log_rmse << ", appearance "
            << narrow.calibration->game_appearance_error << "; 1024 wide: " << wide.calibration->game_per_pixel_log_rmse
            << ", " << wide.calibration->game_appearance_error << "\n";
  EXPECT_LT(wide.calibration->game_per_pixel_log_rmse, 1.15 * narrow.calibration->game_per_pixel_log_rmse);
  EXPECT_LT(wide.calibration->game_appearance_error, 1.15 * narrow.calibration->game_appearance_error + 0.01);
  // A size that is no multiple of the statistics' or the inversion's widths (600x300) is
  // averaged down by area: its clouds are fitted and placed (it used to get no cloud layer,
  // "too small for the cloud statistics"), and judged at 600x300.
  const fit::FitResultFile odd = fit::ReadFitResultFile(s / "out/p600x300/fit.json");
  ASSERT_TRUE(odd.calibration);
  bool inverted = false;
  for (const fit::FitDecision& d : odd.decisions) inverted |= d.what.starts_with("weather map inverted");
  EXPECT_TRUE(inverted);
  EXPECT_EQ(ReadExrRGB(s / "out/p600x300/render.exr").image.width, 600);
  std::cout << "[calibrate] 600 wide: per-pixel " << odd.calibration->game_per_pixel_log_rmse << ", appearance "
            << odd.calibration->game_appearance_error << "\n";
  EXPECT_LT(odd.calibration->game_per_pixel_log_rmse, 1.15 * narrow.calibration->game_per_pixel_log_rmse);
  EXPECT_LT(odd.calibration->game_appearance_error, 1.15 * narrow.calibration->game_appearance_error + 0.01);
}

// How much a lat-long alternates from column to column between 5 and 25 degrees up, over the
// sky pixels: the mean |second difference| of ln luminance across three neighbouring columns.
double ColumnAlternation(const ImageRGB& img, const ImageRGB& mask) {
  const auto ln_y = [&](int x, int y) {
    x = (x + img.width) % img.width;
    return std::log(std::max(1e-12, Rec709Luminance<double>(img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2))));
  };
  double sum = 0.0, n = 0.0;
  for (int y = 0; y < img.height / 2; ++y) {
    const double el = 90.0 - (y + 0.5) * 180.0 / img.height;
    if (el < 5.0 || el > 25.0) continue;
    for (int x = 0; x < img.width; ++x) {
      bool sky = true;
      for (int k = -1; k <= 1; ++k) sky &= mask.at((x + k + img.width) % img.width, y, 0) >= 0.5f;
      if (!sky) continue;
      sum += std::abs(ln_y(x + 1, y) - 2.0 * ln_y(x, y) + ln_y(x - 1, y));
      n += 1.0;
    }
  }
  return n > 0.0 ? sum / n : 0.0;
}

// The bundled partly cloudy photo: the game's clouds near the horizon are drawn as the photo's
// are, not in vertical streaks. When the inversion's renders were half the photo's width,
// every other column of the game's image fell between the rays it followed (measured 1.92x
// the photo's column alternation there; 1.09x at the photo's width then). The bound sits
// between the bug and where the refit's landing spreads without it: 1.18-1.41x over the
// inversion's 5-8 renders (1.28x at calibrate's 6; the landing moves with any small change of
// its start: bench/results/weather_inversion.md, stop 48). The control: the photo with every
// other column of the band scaled by 1.3 is caught.
TEST(Calibrate, ThePartlyCloudyPhotosHorizonCloudsHaveNoStreaks) {
  const std::string path = kRoot + "/datasets/real/sky.exr";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent: run datasets/fetch_real_skies.sh";
  testing::ScratchDir s("calibrate-streaks");
  const auto r = CalibrateQuietly(path, s / "out");
  ASSERT_EQ(r.rc, 0) << r.err;
  const ImageRGB photo = ReadExrRGB(s / "out/sky/photo.exr").image, game = ReadExrRGB(s / "out/sky/render.exr").image;
  const ImageRGB mask = ReadExrRGB(s / "out/sky/mask.exr").image;
  const double photo_alt = ColumnAlternation(photo, mask), game_alt = ColumnAlternation(game, mask);
  std::cout << "[calibrate] column alternation 5-25 deg: photo " << photo_alt << ", game " << game_alt << "\n";
  EXPECT_LT(game_alt, 1.6 * photo_alt);
  ImageRGB striped = photo;
  for (int y = 0; y < striped.height; ++y)
    for (int x = 0; x < striped.width; x += 2)
      for (int c = 0; c < 3; ++c) striped.pixels[3 * (static_cast<size_t>(y) * striped.width + x) + c] *= 1.3f;
  EXPECT_GT(ColumnAlternation(striped, mask), 1.6 * photo_alt);
}

// The mean luminance of `img` within `half_width_deg` of azimuth of `sun`, between two
// elevations (degrees).
double MeanLuminanceBySun(const ImageRGB& img, const std::array<double, 3>& sun, double half_width_deg, double lo_deg,
                          double hi_deg) {
  const double sun_az = latlong::AzimuthDeg(sun);
  double sum = 0.0, n = 0.0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto d = latlong::PixelDirection(x, y, img.width, img.height);
      const double el = latlong::ElevationDeg(d), daz = std::remainder(latlong::AzimuthDeg(d) - sun_az, 360.0);
      if (el < lo_deg || el > hi_deg || std::abs(daz) > half_width_deg) continue;
      const size_t i = 3 * (static_cast<size_t>(y) * img.width + x);
      sum += Rec709Luminance(img.pixels[i], img.pixels[i + 1], img.pixels[i + 2]);
      n += 1.0;
    }
  return n > 0.0 ? sum / n : 0.0;
}

// `dawn` (the sun 13 deg below the horizon, a ridge hiding the sky's lowest 2-4 degrees): the
// game draws the glow down to the horizon where the photo cannot show it. Under the ridge
// the fit keeps the start's shape, and the start's twilight LUT rows had the earth's shadow's
// zeros floored beside entries 1e-3 to 1e-16 of the floor: the glow fell to 0.02 of itself
// within two degrees, a dark band along the horizon (bench/results/horizon_columns.md). The
// control: the game's glow at 4-6 deg against the photo's there, so that a glow made dark all
// over does not pass. Under a civil twilight's sun (the second half) the same start gave no
// glow at all.
TEST(Calibrate, ATwilightGlowReachesTheHorizonUnderTheRidge) {
  const std::string path = kRoot + "/datasets/real/dawn.exr";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent: run datasets/fetch_real_skies.sh";
  testing::ScratchDir s("calibrate-twilight");
  const auto r = CalibrateQuietly(path, s / "out");
  ASSERT_EQ(r.rc, 0) << r.err;
  const fit::FitResultFile f = fit::ReadFitResultFile(s / "out/dawn/fit.json");
  ASSERT_EQ(f.calibration->sky_kind, "twilight");
  const auto sun = f.references.at(0).sun_direction;
  const ImageRGB game = ReadExrRGB(s / "out/dawn/render.exr").image, photo = ReadExrRGB(s / "out/dawn/photo.exr").image;
  const double low = MeanLuminanceBySun(game, sun, 10.0, 0.3, 2.0), glow = MeanLuminanceBySun(game, sun, 10.0, 4.0, 6.0);
  const double photo_glow = MeanLuminanceBySun(photo, sun, 10.0, 4.0, 6.0);
  std::cout << "[calibrate] dawn by the sun: game 0.3-2 deg " << low << ", 4-6 deg " << glow << " (photo " << photo_glow
            << ")\n";
  EXPECT_GT(low, 0.4 * glow);
  EXPECT_GT(glow, 0.5 * photo_glow);
  EXPECT_LT(glow, 2.0 * photo_glow);
  // The same sky under a civil twilight's sun (6 deg down, where the start's Mie table is
  // 1e-4 of its Rayleigh): the glow was not drawn at all (per-pixel log RMSE 0.60 against
  // 0.155 at the sky's own sun estimate); now within 0.01 of it.
  const auto civil =
      CalibrateQuietly(path, s / "civil", " --sun-elevation -6 --sun-azimuth " + std::to_string(latlong::AzimuthDeg(sun)));
  ASSERT_EQ(civil.rc, 0) << civil.err;
  const fit::FitResultFile c = fit::ReadFitResultFile(s / "civil/dawn/fit.json");
  const ImageRGB civil_game = ReadExrRGB(s / "civil/dawn/render.exr").image;
  const auto civil_sun = c.references.at(0).sun_direction;
  const double civil_low = MeanLuminanceBySun(civil_game, civil_sun, 10.0, 0.0, 1.0);
  const double civil_glow = MeanLuminanceBySun(civil_game, civil_sun, 10.0, 4.0, 6.0);
  std::cout << "[calibrate] dawn under a sun 6 deg down: per-pixel " << c.calibration->game_per_pixel_log_rmse
            << " (its own sun's " << f.calibration->game_per_pixel_log_rmse << "); by the sun 0-1 deg up "
            << civil_low << ", 4-6 deg " << civil_glow << "\n";
  EXPECT_LT(c.calibration->game_per_pixel_log_rmse, f.calibration->game_per_pixel_log_rmse + 0.01);
  // No bright line along the hidden horizon: the columns no pixel sees took the change of the
  // nearest seen one on the start's Mie, which rises 1,000x toward the horizon there (0-1 deg
  // up 2.3x the glow at 4-6 deg; the nearest one's value now: 0.56x).
  EXPECT_LT(civil_low, 1.2 * civil_glow);
}

// A time-lapse of two partly cloudy frames 60 s apart under a wind of 12 m/s toward azimuth
// 60 deg (the game's march moving one map and its noise, render --cloud-time): calibrate
// finds one wind for the day from the inverted maps of the frames in DIR (added one command
// at a time), writes it into both presets and day.json, and the first frame's map moved by it predicts the second frame's clouds better
// than the unmoved map (the control). Measured: 10.7 m/s toward 59.6 deg (three frames),
// prediction IoU 0.82 against 0.65 unmoved and 0.88 for the frame's own map.
TEST(Calibrate, ADaysWindFromTwoFrames) {
  testing::ScratchDir s("calibrate-wind");
  ASSERT_EQ(Skycal("weather --seed 5 --size 256 --mean-coverage 0.25 --coverage-contrast 3 --coverage-cells 8 "
                   "--mean-precipitation 0 --out " + s / "w.exr").rc, 0);
  const std::string presets = kRoot + "/datasets/presets/";
  for (const char* f : {"default_cloudy.rayleigh.exr", "default_cloudy.mie.exr", "default_cloudy.sun_transmittance.exr",
                        "default_cloudy.weather.exr"})
    std::filesystem::copy_file(presets + f, s / f);
  nlohmann::json windy = ReadJsonFile(presets + "default_cloudy.json");
  windy["clouds"]["wind_direction"]["value"] = 60.0;
  windy["clouds"]["wind_speed"]["value"] = 12.0;
  WriteJsonFileAtomically(s / "default_cloudy.json", windy);
  for (int t : {0, 60}) {
    const auto rr = Skycal("render --preset " + s / "default_cloudy.json" + " --clouds --weather-map " + s / "w.exr" +
                           " --cloud-time " + std::to_string(t) + " --sun-elevation 40 --sun-azimuth 60 --size 512x256 --out " +
                           s / ("f" + std::to_string(t) + ".exr"));
    ASSERT_EQ(rr.rc, 0) << rr.err;
  }
  // Their capture times, 60 s apart across midnight (local, UTC+2): the EXR's capDate and
  // utcOffset order the frames before render's skycalCloudTimeS would.
  const std::pair<const char*, const char*> stamps[] = {{"f0.exr", "2026-06-21T23:59:30+02:00"},
                                                        {"f60.exr", "2026-06-22T00:00:30+02:00"}};
  for (const auto& [file, when] : stamps) {
    capture::LatLongFrame f = capture::ReadLatLongFrame(s / file);
    capture::TimePlace t;
    t.time_iso8601 = when;
    capture::AddTimePlaceAttributes(t, &f.extra);
    capture::WriteLatLongFrame(s / file, f);
  }
  // One photo a command, the later first (a calibration grows a photo at a time): the first
  // run has no day; the second fits it over both frames in DIR.
  const auto first = CalibrateQuietly(s / "f60.exr", s / "day");
  ASSERT_EQ(first.rc, 0) << first.err;
  EXPECT_FALSE(std::filesystem::exists(s / "day/day.json"));
  const auto a = CalibrateQuietly(s / "f0.exr", s / "day");
  ASSERT_EQ(a.rc, 0) << a.err;
  EXPECT_NE(a.err.find("the day's wind from 2 partly cloudy frames"), std::string::npos) << a.err;
  const nlohmann::json day = ReadJsonFile(s / "day/day.json");
  std::cout << "[calibrate] the day's wind: " << day["wind"].dump() << "\n" << day["pairs"].dump() << "\n";
  EXPECT_NEAR(day["wind"]["speed_m_s"].get<double>(), 12.0, 2.4);
  EXPECT_NEAR(day["wind"]["direction_deg"].get<double>(), 60.0, 5.0);
  EXPECT_EQ(day["time_source"], "capDate + utcOffset");
  ASSERT_EQ(day["pairs"].size(), 1u);
  const nlohmann::json& pair = day["pairs"][0];
  EXPECT_EQ(pair["dt_s"].get<double>(), 60.0);  // in time order, whatever the order given
  EXPECT_GT(pair["predicted_by_the_moved_map"]["cloud_iou"].get<double>(),
            pair["unmoved_map"]["cloud_iou"].get<double>() + 0.1);
  EXPECT_LT(pair["predicted_by_the_moved_map"]["opacity_rms"].get<double>(),
            pair["unmoved_map"]["opacity_rms"].get<double>());
  for (const char* f : {"f0", "f60"}) {
    const nlohmann::json c = ReadJsonFile(s / ("day/" + std::string(f) + "/preset.json")).at("clouds");
    EXPECT_EQ(c["wind_speed"]["value"], day["wind"]["speed_m_s"]) << f;
    EXPECT_EQ(c["wind_direction"]["value"], day["wind"]["direction_deg"]) << f;
  }
  // The report shows it; a day.json without its wind is named by file and field.
  ASSERT_EQ(Skycal("report " + s / "day" + " --out " + s / "day.html").rc, 0);
  std::ifstream page(s / "day.html");
  const std::string html((std::istreambuf_iterator<char>(page)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("The day's wind"), std::string::npos);
  nlohmann::json broken = day;
  broken.erase("wind");
  WriteJsonFileAtomically(s / "day/day.json", broken);
  const auto bad = Skycal("report " + s / "day" + " --out " + s / "bad.html");
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("day.json"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("wind"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(s / "bad.html"));
}

// Each bad photo: exit 1, the file and the reason named, nothing written (DIR not created).
TEST(Calibrate, BadPhotosAreRefusedByNameLeavingNothing) {
  testing::ScratchDir s("calibrate-bad");
  ImageRGB black(128, 64);
  WritePhoto(s / "black.exr", black);
  ImageRGB nan(128, 64);
  for (float& v : nan.pixels) v = std::numeric_limits<float>::quiet_NaN();
  WritePhoto(s / "nan.exr", nan);
  ImageRGB stars(128, 64);  // a dark, grey-orange sky with stars
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      stars.at(x, y, 0) = 0.012f;
      stars.at(x, y, 1) = 0.010f;
      stars.at(x, y, 2) = 0.011f;
    }
  for (int y = 3; y < 24; y += 5)
    for (int x = 2; x < 128; x += 7)
      for (int c = 0; c < 3; ++c) stars.at(x, y, c) = 0.5f;
  WritePhoto(s / "night.exr", stars);
  WriteText(s / "text.exr", "not an EXR");
  struct Case { const char* file; const char* expect; };
  for (const Case c : {Case{"black.exr", "black.exr"}, Case{"nan.exr", "nan.exr"}, Case{"night.exr", "night sky"},
                       Case{"text.exr", "text.exr"}, Case{"missing.exr", "missing.exr"}}) {
    const auto r = Skycal("calibrate --photo " + s / c.file + " --out " + s / "out");
    EXPECT_EQ(r.rc, 1) << c.file << ": " << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.file << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(s / "out")) << c.file;
  }
  ImageRGB square(64, 64);  // not a 2:1 lat-long
  for (float& v : square.pixels) v = 1.0f;
  WriteExrRGB(s / "square.exr", square, {}, ExrPixelType::kFloat);
  const auto q = Skycal("calibrate --photo " + s / "square.exr" + " --out " + s / "out");
  EXPECT_EQ(q.rc, 1);
  EXPECT_NE(q.err.find("square.exr: image is 64x64, expected a 2:1"), std::string::npos) << q.err;
  EXPECT_FALSE(std::filesystem::exists(s / "out"));
  const auto r = Skycal("calibrate --photo " + s / "black.exr" + " --out " + s / "out" + " --lat 45");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--lat"), std::string::npos) << r.err;
}
#endif

}  // namespace
}  // namespace skycal
