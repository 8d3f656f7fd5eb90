// Tests for skycal_color: the repo's OCIO config, display previews and conversions.
// Every test names the config explicitly so a developer's $OCIO cannot change results.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "skycal/color/preview.h"
#include "skycal/core/error.h"

namespace skycal::color {
namespace {

namespace fs = std::filesystem;

#ifndef SKYCAL_SOURCE_DIR
#error "SKYCAL_SOURCE_DIR must be defined (the skycal_test() CMake helper does it)"
#endif
const std::string kConfig = std::string(SKYCAL_SOURCE_DIR) + "/config/skycal.ocio";
constexpr char kFilmicView[] = "ACES 1.0 - SDR Video";
constexpr char kPlainView[] = "Un-tone-mapped";

ImageRGB Grey(const std::vector<float>& values) {
  ImageRGB img(static_cast<int>(values.size()), 1);
  for (size_t i = 0; i < values.size(); ++i) {
    for (int c = 0; c < 3; ++c) img.at(static_cast<int>(i), 0, c) = values[i];
  }
  return img;
}

PreviewOptions Options(const std::string& view, double ev) {
  PreviewOptions o;
  o.config_path = kConfig;
  o.view = view;
  o.exposure_ev = ev;
  return o;
}

// A fresh, empty scratch directory per test.
fs::path ScratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 ("skycal_color_test_" + std::to_string(::getpid()) + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

size_t CountEntries(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

// Runs `fn`, expects a skycal::Error whose message contains every string in `needles`.
template <typename Fn>
void ExpectErrorNaming(Fn fn, const std::vector<std::string>& needles) {
  try {
    fn();
    ADD_FAILURE() << "expected skycal::Error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    for (const auto& n : needles) EXPECT_NE(msg.find(n), std::string::npos) << "'" << n << "' not in: " << msg;
  }
}

// (a) lin_rec709 -> ACEScg of pure red is the first column of the published
// Rec.709 -> AP1 (Bradford) matrix; the round trip is identity.
TEST(ColorConvert, Rec709RedToAcesCgMatchesAp1Matrix) {
  ImageRGB img(2, 1);
  img.at(0, 0, 0) = 1.0f;  // pure red
  const float mixed[3] = {0.25f, 3.5f, 0.01f};
  for (int c = 0; c < 3; ++c) img.at(1, 0, c) = mixed[c];
  const ImageRGB original = img;

  ConvertColorspace(img, "lin_rec709", "ACEScg", kConfig);
  EXPECT_NEAR(img.at(0, 0, 0), 0.6131, 1e-3);
  EXPECT_NEAR(img.at(0, 0, 1), 0.0702, 1e-3);
  EXPECT_NEAR(img.at(0, 0, 2), 0.0206, 1e-3);
  std::printf("[measured] lin_rec709 (1,0,0) -> ACEScg (%.6f, %.6f, %.6f)\n", img.at(0, 0, 0), img.at(0, 0, 1),
              img.at(0, 0, 2));

  ConvertColorspace(img, "ACEScg", "lin_rec709", kConfig);
  double worst = 0.0;
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_NEAR(img.pixels[i], original.pixels[i], 1e-5) << "value " << i;
    worst = std::max(worst, std::fabs(double(img.pixels[i]) - original.pixels[i]));
  }
  std::printf("[measured] round-trip max abs error %.3g\n", worst);
}

// Roles resolve like colour spaces; ACES2065-1 of white is still neutral.
TEST(ColorConvert, RolesAndAces2065) {
  ImageRGB img = Grey({1.0f});
  ConvertColorspace(img, "scene_linear", "ACES2065-1", kConfig);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.at(0, 0, c), 1.0, 1e-4);
}

// (b) The un-tone-mapped view is a clamp plus the sRGB curve: 0.18 -> 0.4613 (~118).
TEST(ColorPreview, UntonemappedIsSrgbCurve) {
  PreviewReport rep;
  const auto out = ToDisplay8(Grey({0.0f, 0.18f, 1.0f, 4.0f}), Options(kPlainView, 0.0), &rep);
  ASSERT_EQ(out.size(), 12u);
  EXPECT_EQ(rep.view, kPlainView);
  EXPECT_EQ(rep.exposure_ev, 0.0);
  EXPECT_FALSE(rep.auto_exposure);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(out[0 + c], 0);
    EXPECT_NEAR(out[3 + c], 0.4613 * 255.0, 1.0);
    EXPECT_EQ(out[6 + c], 255);
    EXPECT_EQ(out[9 + c], 255);  // clamped, not wrapped
  }
  std::printf("[measured] Un-tone-mapped: 0.18 -> %d/255, 1.0 -> %d/255\n", out[3], out[6]);
}

// Exposure is a 2^ev multiply before the view: 0.09 at +1 EV looks like 0.18 at 0 EV.
TEST(ColorPreview, ExposureIsPowerOfTwoScale) {
  const auto a = ToDisplay8(Grey({0.09f}), Options(kPlainView, 1.0), nullptr);
  const auto b = ToDisplay8(Grey({0.18f}), Options(kPlainView, 0.0), nullptr);
  EXPECT_EQ(a, b);
}

// (c) The default view is the filmic one, monotonic on a ramp, and black stays black.
TEST(ColorPreview, DefaultViewIsMonotonicFilmic) {
  std::vector<float> ramp = {0.0f};
  for (double ev = -14.0; ev <= 14.0; ev += 0.125) ramp.push_back(static_cast<float>(0.18 * std::exp2(ev)));
  PreviewOptions o = Options("", 0.0);
  PreviewReport rep;
  const auto out = ToDisplay8(Grey(ramp), o, &rep);
  EXPECT_EQ(rep.view, kFilmicView);
  EXPECT_EQ(rep.config_path, kConfig);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out[c], 0) << "black";
  for (size_t i = 1; i < ramp.size(); ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_GE(out[i * 3 + c], out[(i - 1) * 3 + c]) << "ramp step " << i;
  }
  // A filmic curve keeps highlight detail: 1.0 is not yet white, 2^14 * 0.18 is.
  const size_t one = 1 + static_cast<size_t>(std::lround((std::log2(1.0 / 0.18) + 14.0) * 8));
  EXPECT_LT(out[one * 3], 255);
  EXPECT_GE(out[(ramp.size() - 1) * 3], 250);
  // Mid grey lands mid-scale: ACES 1.0 SDR renders 0.18 darker than a plain sRGB curve
  // does (measured code 91, i.e. 0.357 encoded, vs 118 un-tone-mapped).
  const size_t grey = 1 + 14 * 8;
  EXPECT_GT(out[grey * 3], 80);
  EXPECT_LT(out[grey * 3], 130);
  std::printf("[measured] %s: 0 -> %d, 0.18 -> %d, ~1.0 -> %d, 2949 -> %d\n", kFilmicView, out[0], out[grey * 3],
              out[one * 3], out[(ramp.size() - 1) * 3]);
}

// (d) Automatic exposure maps the log-average luminance to 0.18.
TEST(ColorPreview, AutoExposureUniformImage) {
  ImageRGB img(8, 4);
  std::fill(img.pixels.begin(), img.pixels.end(), 1000.0f);
  PreviewReport rep;
  const auto out = ToDisplay8(img, Options(kPlainView, NAN), &rep);
  EXPECT_TRUE(rep.auto_exposure);
  EXPECT_NEAR(rep.exposure_ev, std::log2(0.18 / 1000.0), 1e-6);
  ASSERT_FALSE(rep.notes.empty());
  EXPECT_NE(rep.notes[0].find("automatic exposure"), std::string::npos) << rep.notes[0];
  EXPECT_NEAR(out[0], 0.4613 * 255.0, 1.0);  // the image now shows as mid grey
  std::printf("[measured] auto exposure %.9f EV (expected %.9f); note: %s\n", rep.exposure_ev,
              std::log2(0.18 / 1000.0), rep.notes[0].c_str());
}

// Auto exposure ignores non-finite and non-positive pixels; all-black falls back to 0 EV.
TEST(ColorPreview, AutoExposureSkipsBadPixels) {
  const float inf = std::numeric_limits<float>::infinity();
  PreviewReport rep;
  ToDisplay8(Grey({2.0f, 8.0f, NAN, inf, -5.0f, 0.0f}), Options(kPlainView, NAN), &rep);
  EXPECT_NEAR(rep.exposure_ev, std::log2(0.18 / 4.0), 1e-6);  // geometric mean of 2 and 8
  ToDisplay8(Grey({0.0f, -1.0f}), Options(kPlainView, NAN), &rep);
  EXPECT_EQ(rep.exposure_ev, 0.0);
}

// (e) Bad input: each failure names the culprit and leaves no file behind.
TEST(ColorPreview, BadInputNamesCulpritAndLeavesNoFile) {
  const fs::path dir = ScratchDir();
  const std::string png = (dir / "out.png").string();
  const ImageRGB img = Grey({0.1f, 0.5f});

  PreviewOptions o = Options("", 0.0);
  o.input_colorspace = "lin_rec2020_nope";
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {"lin_rec2020_nope", kConfig, png});

  o = Options("Filmic Nope", 0.0);
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {"Filmic Nope", "sRGB", kConfig});

  o = Options("", 0.0);
  o.display = "P3 Nope";
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {"P3 Nope"});

  o = Options("", 0.0);
  o.config_path = (dir / "missing.ocio").string();
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {o.config_path});

  o = Options("", 0.0);
  o.config_path = (dir / "garbage.ocio").string();
  { std::ofstream(o.config_path) << "this: [is not an OCIO config\n"; }
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {o.config_path});
  fs::remove(o.config_path);

  o = Options("", 99.0);
  ExpectErrorNaming([&] { WritePreviewPng(img, png, o); }, {"exposure_ev"});

  const std::string no_dir = (dir / "no_such_dir" / "out.png").string();
  ExpectErrorNaming([&] { WritePreviewPng(img, no_dir, Options("", 0.0)); }, {no_dir});

  ExpectErrorNaming([&] { WritePreviewPng(ImageRGB(), png, Options("", 0.0)); }, {png, "empty"});

  ImageRGB conv = img;
  ExpectErrorNaming([&] { ConvertColorspace(conv, "lin_rec709", "ACEScg_nope", kConfig); }, {"ACEScg_nope"});
  EXPECT_EQ(conv.pixels, img.pixels);

  EXPECT_EQ(CountEntries(dir), 0u) << "a failed write left a file in " << dir;
  fs::remove_all(dir);
}

// (e, cont.) A read-only directory is refused; root bypasses permissions, so skip there.
TEST(ColorPreview, ReadOnlyDirectoryIsRefused) {
  if (::geteuid() == 0) GTEST_SKIP() << "running as root: permissions are not enforced";
  const fs::path dir = ScratchDir();
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec);
  const std::string png = (dir / "out.png").string();
  ExpectErrorNaming([&] { WritePreviewPng(Grey({0.5f}), png, Options("", 0.0)); }, {png});
  fs::permissions(dir, fs::perms::owner_all);
  EXPECT_EQ(CountEntries(dir), 0u);
  fs::remove_all(dir);
}

// (f) NaN, Inf and negative values give valid 8-bit output in both views.
TEST(ColorPreview, NonFiniteAndNegativePixels) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> values = {nan, inf, -inf, -0.5f, 0.18f, std::numeric_limits<float>::max()};
  for (const char* view : {kFilmicView, kPlainView}) {
    for (double ev : {0.0, double(NAN), 20.0, -20.0}) {
      PreviewReport rep;
      const auto out = ToDisplay8(Grey(values), Options(view, ev), &rep);
      ASSERT_EQ(out.size(), values.size() * 3);
      ASSERT_FALSE(rep.notes.empty());
      EXPECT_TRUE(std::isfinite(rep.exposure_ev));
      if (ev == 0.0) {
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(out[0 * 3 + c], 0) << view << ": NaN -> black";
          EXPECT_GE(out[1 * 3 + c], 250) << view << ": +Inf -> white";
          EXPECT_EQ(out[2 * 3 + c], 0) << view << ": -Inf -> black";
          EXPECT_EQ(out[3 * 3 + c], 0) << view << ": negative -> black";
        }
      }
    }
  }
  // Mixed channels: a NaN in one channel only zeroes that channel.
  ImageRGB img(1, 1);
  img.at(0, 0, 0) = 1.0f;
  img.at(0, 0, 1) = nan;
  img.at(0, 0, 2) = -2.0f;
  const auto out = ToDisplay8(img, Options(kPlainView, 0.0), nullptr);
  EXPECT_EQ(out[0], 255);
  EXPECT_EQ(out[1], 0);
  EXPECT_EQ(out[2], 0);
}

// The PNG round-trips through a decoder with RGB order and row 0 on top intact.
TEST(ColorPreview, WritesPngAtomically) {
  const fs::path dir = ScratchDir();
  const std::string png = (dir / "sky.png").string();
  ImageRGB img(3, 2);
  img.at(0, 0, 0) = 1.0f;  // top-left red
  img.at(2, 1, 2) = 1.0f;  // bottom-right blue
  const PreviewReport rep = WritePreviewPng(img, png, Options(kPlainView, 0.0));
  EXPECT_EQ(rep.view, kPlainView);
  EXPECT_EQ(CountEntries(dir), 1u) << "temporary file left beside the PNG";
  const cv::Mat bgr = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(bgr.empty());
  ASSERT_EQ(bgr.type(), CV_8UC3);
  EXPECT_EQ(bgr.cols, 3);
  EXPECT_EQ(bgr.rows, 2);
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 2), cv::Vec3b(255, 0, 0));
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 0), cv::Vec3b(0, 0, 0));
  // Overwriting an existing preview works (rename replaces it).
  WritePreviewPng(img, png, Options("", 0.0));
  EXPECT_EQ(CountEntries(dir), 1u);
  fs::remove_all(dir);
}

TEST(ColorPreview, OptionsValidation) {
  std::string why;
  EXPECT_TRUE(PreviewOptions{}.IsValid(&why));
  PreviewOptions o;
  o.exposure_ev = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("exposure_ev"), std::string::npos);
  o = PreviewOptions{};
  o.input_colorspace.clear();
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("input_colorspace"), std::string::npos);
  o = PreviewOptions{};
  o.display.clear();
  EXPECT_FALSE(o.IsValid(nullptr));
}

// The parsed config is kept per file version: a conversion through an edited config sees the
// edit (a colour space renamed away is unknown at once), and its first version still converts.
TEST(ColorConfig, AnEditedConfigIsReadAgain) {
  const fs::path dir = ScratchDir();
  const std::string path = (dir / "studio.ocio").string();
  std::string text;
  {
    std::ifstream in(kConfig);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string from = "name: ACEScg", to = "name: ACEScg_renamed_by_the_studio";
  ASSERT_NE(text.find(from), std::string::npos);
  std::ofstream(path) << text;
  ImageRGB red = Grey({0.0f});
  red.at(0, 0, 0) = 1.0f;
  ImageRGB first = red;
  ConvertColorspace(first, "lin_rec709", "ACEScg", path);  // parsed and kept
  ConvertColorspace(first, "ACEScg", "lin_rec709", path);  // from the kept parse
  EXPECT_NEAR(first.at(0, 0, 0), 1.0f, 1e-5f);
  std::ofstream(path) << text.replace(text.find(from), from.size(), to);  // a longer file: its size differs
  ImageRGB second = red;
  ExpectErrorNaming([&] { ConvertColorspace(second, "lin_rec709", "ACEScg", path); }, {"ACEScg", path});
  ConvertColorspace(second, "lin_rec709", "ACEScg_renamed_by_the_studio", path);
  ImageRGB reference = red;
  ConvertColorspace(reference, "lin_rec709", "ACEScg", kConfig);
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(second.at(0, 0, c), reference.at(0, 0, c));
  fs::remove_all(dir);
}

// $OCIO overrides the repo config; unset, the repo config is used.
TEST(ColorConfig, DefaultConfigPathHonoursEnv) {
  const char* saved = std::getenv("OCIO");
  const std::string saved_value = saved ? saved : "";
  ::unsetenv("OCIO");
  EXPECT_EQ(DefaultConfigPath(), kConfig);
  EXPECT_TRUE(fs::exists(DefaultConfigPath()));
  ::setenv("OCIO", "/studio/config.ocio", 1);
  EXPECT_EQ(DefaultConfigPath(), "/studio/config.ocio");
  ::setenv("OCIO", "", 1);
  EXPECT_EQ(DefaultConfigPath(), kConfig);
  if (saved) {
    ::setenv("OCIO", saved_value.c_str(), 1);
  } else {
    ::unsetenv("OCIO");
  }
}

}  // namespace
}  // namespace skycal::color
