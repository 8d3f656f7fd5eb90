// Reliability through the binary: an optional plot never ends a job (PLplot without its
// drivers), a single-file output never replaces a file of another kind or a page skycal did
// not write, a preset interrupted between its files is still one whole preset, no NaN or
// inf is ever written (crafted EXRs), and EXR windows and output extensions are checked.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/sha256.h"
#include "test_util.h"

namespace skycal {
namespace {
namespace fs = std::filesystem;

using testing::ProcessResult;
using testing::ScratchDir;

ProcessResult Skycal(const std::string& args, const std::string& env = "") {
  return testing::RunSkycal(SKYCAL_BINARY, args, env);
}

const std::string kSun = " --sun-elevation 20 --sun-azimuth 30 ";

std::string Render(const ScratchDir& dir, const std::string& name, const std::string& size = "64x32") {
  const ProcessResult r = Skycal("render" + kSun + "--size " + size + " --backend cpu --out " + (dir / name));
  EXPECT_EQ(r.rc, 0) << r.err;
  return dir / name;
}

bool Has(const std::string& text, const std::string& needle) { return text.find(needle) != std::string::npos; }

long long NonFinite(const ImageRGB& img) {
  long long n = 0;
  for (float v : img.pixels) n += std::isfinite(v) ? 0 : 1;
  return n;
}

TEST(Reliability, PlotsWithoutPlplotDriversAreSkippedAndTheFitKept) {
  ScratchDir dir("rel-plplot");
  const std::string sky = Render(dir, "sky.exr");
  fs::create_directory(dir.path() / "no-drivers");
  for (const std::string& drv : {dir / "no-drivers", dir / "absent"}) {
    const std::string out = dir / ("fit-" + fs::path(drv).filename().string());
    const ProcessResult r =
        Skycal("fit --quiet --backend cpu --reference " + sky + " --out " + out, "PLPLOT_DRV_DIR=" + drv);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(Has(r.err, "plots skipped")) << r.err;
    EXPECT_TRUE(Has(r.err, drv)) << "the message names the driver directory: " << r.err;
    EXPECT_FALSE(Has(r.err, "Program aborted")) << r.err;
    EXPECT_TRUE(fs::exists(out + "/fit.json"));
    EXPECT_TRUE(fs::exists(out + "/preset.json"));
    const std::string page = testing::Slurp(out + "/report.html");
    EXPECT_TRUE(Has(page, "plot left out")) << "the page says where each plot would be";
    // `report` alone on the same output: the page without plots, exit 0.
    const ProcessResult rep = Skycal("report " + out + " --out " + (dir / "r.html") + " --json", "PLPLOT_DRV_DIR=" + drv);
    ASSERT_EQ(rep.rc, 0) << rep.err;
    EXPECT_TRUE(Has(rep.err, "plots skipped")) << rep.err;
    const nlohmann::json j = nlohmann::json::parse(rep.out);
    EXPECT_EQ(j["plots"], 0);
    EXPECT_GT(j["plots_skipped"].get<int>(), 0);
  }
  // With the drivers, the same fit draws its plots.
  const ProcessResult ok = Skycal("report " + (dir / "fit-no-drivers") + " --out " + (dir / "r.html") + " --json");
  ASSERT_EQ(ok.rc, 0) << ok.err;
  EXPECT_FALSE(Has(ok.err, "plots skipped")) << ok.err;
  const nlohmann::json j = nlohmann::json::parse(ok.out);
  EXPECT_EQ(j["plots_skipped"], 0);
  EXPECT_GT(j["plots"].get<int>(), 0);
  for (const auto& e : fs::directory_iterator(dir.path())) {
    EXPECT_NE(e.path().filename().string().rfind(".", 0), 0u) << "left behind: " << e.path();
  }
}

TEST(Reliability, AMissingOcioConfigLeavesThePreviewsOutNotTheFit) {
  ScratchDir dir("rel-ocio");
  const std::string sky = Render(dir, "sky.exr");
  const ProcessResult r = Skycal("fit --quiet --backend cpu --reference " + sky + " --out " + (dir / "out"),
                                 "OCIO=" + (dir / "missing.ocio"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(Has(r.err, "previews skipped") && Has(r.err, "missing.ocio")) << r.err;
  EXPECT_TRUE(fs::exists(dir / "out/preset.json"));
  EXPECT_TRUE(fs::exists(dir / "out/fit.json"));
  EXPECT_TRUE(fs::exists(dir / "out/report.html"));
  EXPECT_FALSE(fs::exists(dir / "out/report.png"));
}

// Runs the command; expects exit 1, `needle` in stderr, and `victim` byte-identical.
void ExpectKept(const std::string& args, const std::string& needle, const std::string& victim) {
  const std::string before = Sha256OfFile(victim);
  const ProcessResult r = Skycal(args);
  EXPECT_EQ(r.rc, 1) << args << "\n" << r.err;
  EXPECT_TRUE(Has(r.err, needle)) << "expected '" << needle << "' in: " << r.err;
  EXPECT_EQ(Sha256OfFile(victim), before) << victim << " was replaced by: " << args;
}

TEST(Reliability, ASingleFileOutputNeverReplacesAFileItDidNotMake) {
  ScratchDir dir("rel-kinds");
  const std::string sky = Render(dir, "sky.exr");
  ASSERT_EQ(Skycal("bake --out " + (dir / "p.json")).rc, 0);
  ASSERT_EQ(Skycal("export --preset " + (dir / "p.json") + " --out " + (dir / "game") + " --no-report").rc, 0);
  testing::WriteText(dir / "notes.csv", "a,b\n1,2\n");
  testing::WriteText(dir / "mine.html", "<html><body>my own page</body></html>\n");
  const std::string report = "report " + (dir / "game") + " --out ";
  ExpectKept(report + (dir / "notes.csv"), "ending in .html", dir / "notes.csv");
  ExpectKept(report + (dir / "p.mie.exr"), "ending in .html", dir / "p.mie.exr");
  ExpectKept(report + (dir / "mine.html"), "did not write", dir / "mine.html");
  // Its own page: replaced.
  ASSERT_EQ(Skycal(report + (dir / "r.html")).rc, 0);
  const ProcessResult again = Skycal(report + (dir / "r.html"));
  EXPECT_EQ(again.rc, 0) << again.err;
  // The same rule in every writer: a CSV renamed .exr, a text renamed .json, a FIFO.
  fs::copy(dir / "notes.csv", dir / "data.exr");
  ExpectKept("render" + kSun + "--size 64x32 --backend cpu --out " + (dir / "data.exr"), "not an OpenEXR file",
             dir / "data.exr");
  // An EXR over a preset's LUT (not this verb's input): the preset would no longer load.
  ExpectKept("render" + kSun + "--size 64x32 --backend cpu --out " + (dir / "p.mie.exr"), "LUT table", dir / "p.mie.exr");
  ExpectKept("weather --size 16 --out " + (dir / "notes.csv"), "ending in .exr", dir / "notes.csv");
  testing::WriteText(dir / "notes.json", "not json\n");
  ExpectKept("bake --out " + (dir / "notes.json"), "not a JSON file", dir / "notes.json");
  ExpectKept("probe-extract --image " + sky + " --out " + (dir / "notes.json"), "not a JSON file", dir / "notes.json");
  fs::copy(dir / "notes.csv", dir / "photo.png");
  ExpectKept("render" + kSun + "--size 64x32 --backend cpu --out " + (dir / "x.exr") + " --png " + (dir / "photo.png"),
             "not a PNG file", dir / "photo.png");
  EXPECT_FALSE(fs::exists(dir / "x.exr")) << "refused before the work";
}

TEST(Reliability, APresetInterruptedBetweenItsFilesIsOneWholePreset) {
  ScratchDir dir("rel-bake");
  ASSERT_EQ(Skycal("bake --n-gamma 32 --out " + (dir / "p.json")).rc, 0);
  fs::create_directory(dir.path() / "new");
  ASSERT_EQ(Skycal("bake --n-gamma 48 --out " + (dir / "new/p.json")).rc, 0);
  const std::vector<std::string> luts = {"p.rayleigh.exr", "p.mie.exr", "p.sun_transmittance.exr"};
  for (int stop_after : {1, 2, 3}) {
    const ProcessResult r = Skycal("bake --n-gamma 48 --out " + (dir / "p.json"),
                                   "SKYCAL_TEST_STOP_BETWEEN_FILES=" + std::to_string(stop_after));
    // 143: the watcher exited once the renames were done; 0: the verb returned first.
    EXPECT_TRUE(r.rc == 128 + 15 || r.rc == 0) << "SIGTERM after file " << stop_after << ": " << r.rc << " " << r.err;
    // Every LUT is the new bake's: the renames finished as one unit before the exit.
    for (const std::string& l : luts) {
      EXPECT_EQ(Sha256OfFile(dir / l), Sha256OfFile(dir / ("new/" + l))) << l << " after stop " << stop_after;
    }
    const ProcessResult use = Skycal("render" + kSun + "--size 32x16 --backend cpu --preset " + (dir / "p.json") +
                                     " --out " + (dir / "check.exr"));
    EXPECT_EQ(use.rc, 0) << "the preset loads after stop " << stop_after << ": " << use.err;
    for (const auto& e : fs::directory_iterator(dir.path())) {
      EXPECT_NE(e.path().filename().string().rfind(".", 0), 0u) << "left behind: " << e.path();
    }
    ASSERT_EQ(Skycal("bake --n-gamma 32 --out " + (dir / "p.json")).rc, 0);  // back to the old one
  }
}

// Entries of `dir` whose name starts with '.' (staging directories, temporaries).
std::vector<std::string> Hidden(const ScratchDir& dir) {
  std::vector<std::string> hidden;
  for (const auto& e : fs::directory_iterator(dir.path()))
    if (e.path().filename().string().rfind(".", 0) == 0) hidden.push_back(e.path().filename().string());
  return hidden;
}

TEST(Reliability, AFailedPreviewKeepsTheEarlierRendersExr) {
  // render --png with OCIO naming a missing config: the preview fails after the EXR was
  // rendered; the EXR that was there before the run stays byte for byte, no PNG appears.
  ScratchDir dir("rel-render-png");
  const std::string exr = Render(dir, "sky.exr");
  const std::string before = Sha256OfFile(exr);
  const ProcessResult r = Skycal("render" + kSun + "--size 32x16 --backend cpu --out " + exr + " --png " +
                                     (dir / "sky.png"),
                                 "OCIO=" + (dir / "missing.ocio"));
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "missing.ocio")) << r.err;
  EXPECT_FALSE(Has(r.err, ".tmp-")) << "the message names a staging path: " << r.err;
  EXPECT_EQ(Sha256OfFile(exr), before);
  EXPECT_FALSE(fs::exists(dir / "sky.png"));
  EXPECT_EQ(Hidden(dir), std::vector<std::string>{});
  // Both written: the new EXR and its PNG together.
  const ProcessResult ok =
      Skycal("render" + kSun + "--size 32x16 --backend cpu --out " + exr + " --png " + (dir / "sky.png"));
  ASSERT_EQ(ok.rc, 0) << ok.err;
  EXPECT_NE(Sha256OfFile(exr), before);
  EXPECT_TRUE(fs::is_regular_file(dir / "sky.png"));
  EXPECT_EQ(Hidden(dir), std::vector<std::string>{});
}

TEST(Reliability, AFlowWhoseSidecarCannotBeWrittenKeepsThePreviousVectors) {
  // The sidecar's path is a directory: the run fails, and the previous run's EXR and PNG
  // are kept (they used to be replaced, then removed when the sidecar failed).
  ScratchDir dir("rel-flow");
  const std::string a = Render(dir, "a.exr");
  const ProcessResult rb = Skycal(" render --sun-elevation 20 --sun-azimuth 34 --size 64x32 --backend cpu --out " +
                                  (dir / "b.exr"));
  ASSERT_EQ(rb.rc, 0) << rb.err;
  ASSERT_EQ(Skycal("flow " + a + " " + (dir / "b.exr") + " --out " + (dir / "v.exr")).rc, 0);
  const std::string exr_before = Sha256OfFile(dir / "v.exr"), png_before = Sha256OfFile(dir / "v.png");
  fs::remove(dir / "v.json");
  fs::create_directory(dir / "v.json");
  const ProcessResult r = Skycal("flow " + (dir / "b.exr") + " " + a + " --out " + (dir / "v.exr"));
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_TRUE(Has(r.err, dir / "v.json")) << r.err;
  ASSERT_TRUE(fs::exists(dir / "v.exr"));
  ASSERT_TRUE(fs::exists(dir / "v.png"));
  EXPECT_EQ(Sha256OfFile(dir / "v.exr"), exr_before);
  EXPECT_EQ(Sha256OfFile(dir / "v.png"), png_before);
  EXPECT_TRUE(fs::is_directory(dir / "v.json"));
  EXPECT_EQ(Hidden(dir), std::vector<std::string>{});
}

TEST(Reliability, TheCloudNoiseCacheNeverCreatesAMissingHome) {
  // HOME names a missing directory (XDG_CACHE_HOME unset): the render succeeds with one
  // warning line and creates nothing; XDG_CACHE_HOME under a missing parent, the same; an
  // existing HOME gets $HOME/.cache/skycal with the cache file.
  ScratchDir dir("rel-noise-home");
  const std::string clouds = "render" + kSun + "--size 32x16 --backend cpu --clouds --out ";
  const struct {
    std::string env, missing;
  } cases[] = {{"env -u XDG_CACHE_HOME HOME=" + (dir / "missing"), dir / "missing"},
               {"XDG_CACHE_HOME=" + (dir / "gone/cache"), dir / "gone"}};
  for (const auto& c : cases) {
    const ProcessResult r = Skycal(clouds + (dir / "c.exr"), c.env);
    ASSERT_EQ(r.rc, 0) << c.env << ": " << r.err;
    EXPECT_FALSE(fs::exists(c.missing)) << c.env;
    size_t lines = 0;
    for (size_t at = r.err.find("cloud noise not cached"); at != std::string::npos;
         at = r.err.find("cloud noise not cached", at + 1))
      ++lines;
    EXPECT_EQ(lines, 1u) << r.err;
    EXPECT_TRUE(Has(r.err, "'" + c.missing + "'")) << r.err;
  }
  fs::create_directory(dir.path() / "home");
  const ProcessResult r = Skycal(clouds + (dir / "c.exr"), "env -u XDG_CACHE_HOME HOME=" + (dir / "home"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(Has(r.err, "cloud noise not cached")) << r.err;
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "home/.cache/skycal")) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

// A 64 x 32 lat-long of the binary's render with NaN and +inf written into two columns.
std::string DirtyFrame(const ScratchDir& dir, const std::string& clean) {
  capture::LatLongFrame f = capture::ReadLatLongFrame(clean);
  f.radiance.at(10, 5, 1) = std::numeric_limits<float>::quiet_NaN();
  f.radiance.at(20, 8, 0) = std::numeric_limits<float>::infinity();
  capture::WriteLatLongFrame(dir / "dirty.exr", f);
  return dir / "dirty.exr";
}

TEST(Reliability, ResampleMasksInvalidPixelsInsteadOfSpreadingThem) {
  ScratchDir dir("rel-resample");
  const std::string clean = Render(dir, "clean.exr");
  const std::string dirty = DirtyFrame(dir, clean);
  ASSERT_EQ(Skycal("resample --in " + clean + " --out " + (dir / "a.exr")).rc, 0);
  const ProcessResult r = Skycal("resample --in " + dirty + " --out " + (dir / "b.exr"));
  ASSERT_EQ(r.rc, 0) << r.err;
  const ImageRGB a = ReadExrRGB(dir / "a.exr").image, b = ReadExrRGB(dir / "b.exr").image;
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  EXPECT_EQ(NonFinite(b), 0);
  int far_rows = 0;
  for (int y = 0; y < b.height; ++y) {
    for (int x = 0; x < b.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const bool touched = (x == 10 && c == 1) || (x == 20 && c == 0);
        if (!touched) {
          EXPECT_EQ(a.at(x, y, c), b.at(x, y, c)) << x << "," << y << "," << c;
        }
      }
    }
    // Rows well below the invalid pixels (rows 5 and 8 of 32, upper sky): their own values.
    if (y > b.height / 2) {
      EXPECT_NEAR(b.at(10, y, 1), a.at(10, y, 1), 1e-5 * std::abs(a.at(10, y, 1)) + 1e-9);
      EXPECT_NEAR(b.at(20, y, 0), a.at(20, y, 0), 1e-5 * std::abs(a.at(20, y, 0)) + 1e-9);
      ++far_rows;
    }
  }
  EXPECT_GT(far_rows, 5);
}

TEST(Reliability, NoVerbWritesNanOrInf) {
  ScratchDir dir("rel-finite");
  const std::string clean = Render(dir, "clean.exr");
  const std::string dirty = DirtyFrame(dir, clean);
  // import: invalid pixels written as 0 (masked by the fit like values <= 0), counted.
  const ProcessResult imp = Skycal("import --in " + dirty + " --out " + (dir / "imp.exr") + " --json");
  ASSERT_EQ(imp.rc, 0) << imp.err;
  EXPECT_EQ(NonFinite(ReadExrRGB(dir / "imp.exr").image), 0);
  EXPECT_TRUE(Has(imp.err, "written as 0")) << imp.err;
  // stars: a star beside a NaN and an inf; the replacement stays finite.
  ImageRGB night(128, 64);
  for (float& v : night.pixels) v = 1.0f;
  for (int c = 0; c < 3; ++c) night.at(40, 20, c) = 60.0f;  // the star
  night.at(44, 20, 1) = std::numeric_limits<float>::quiet_NaN();  // in the replacement's pairs
  night.at(40, 24, 0) = std::numeric_limits<float>::infinity();    // likewise; itself a "star"
  WriteExrRGB(dir / "night.exr", night, {});
  const ProcessResult st = Skycal("stars --reference " + (dir / "night.exr") + " --out " + (dir / "clean-night.exr"));
  ASSERT_EQ(st.rc, 0) << st.err;
  const ImageRGB out = ReadExrRGB(dir / "clean-night.exr").image;
  EXPECT_EQ(NonFinite(out), 0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at(40, 20, c), 1.0f, 1e-6) << "the star replaced by its sky";
  EXPECT_EQ(out.at(44, 20, 1), 0.0f);  // an invalid pixel left alone: written as 0
  // --half at the sun: clamped to 65504, counted, never +inf.
  const ProcessResult half =
      Skycal("render" + kSun + "--size 2048x1024 --backend cpu --half --out " + (dir / "half.exr"));
  ASSERT_EQ(half.rc, 0) << half.err;
  EXPECT_TRUE(Has(half.err, "clamped to 65504")) << half.err;
  const ImageRGB h = ReadExrRGB(dir / "half.exr").image;
  EXPECT_EQ(NonFinite(h), 0);
  float peak = 0.0f;
  for (float v : h.pixels) peak = std::max(peak, v);
  EXPECT_EQ(peak, 65504.0f);
}

TEST(Reliability, DegenerateFramesAreRefusedWithTheirCounts) {
  ScratchDir dir("rel-degenerate");
  const std::string sky = Render(dir, "sky.exr");
  for (const float v : {std::numeric_limits<float>::quiet_NaN(), 0.0f, -1.0f}) {
    capture::LatLongFrame f = capture::ReadLatLongFrame(sky);  // its sun attribute kept
    for (float& p : f.radiance.pixels) p = v;
    if (std::isnan(v)) f.radiance.at(3, 3, 0) = f.radiance.at(3, 3, 1) = f.radiance.at(3, 3, 2) = 1.0f;  // 1 of 2048
    capture::WriteLatLongFrame(dir / "bad.exr", f);
    const std::string bad = dir / "bad.exr";
    for (const std::string& cmd : {"mask --reference " + bad + " --out " + (dir / "m.exr"),
                                   "import --in " + bad + " --out " + (dir / "i.exr"),
                                   "probe-extract --image " + bad + " --out " + (dir / "s.json"),
                                   "fit --quiet --backend cpu --reference " + bad + " --out " + (dir / "fit"),
                                   "ceiling --reference " + bad}) {
      const ProcessResult r = Skycal(cmd);
      EXPECT_EQ(r.rc, 1) << v << ": " << cmd << "\n" << r.err;
      EXPECT_TRUE(Has(r.err, "bad.exr") && (Has(r.err, "pixels are valid") || Has(r.err, "no valid sky pixel")))
          << v << ": " << cmd << "\n" << r.err;
    }
    EXPECT_FALSE(fs::exists(dir / "m.exr") || fs::exists(dir / "i.exr") || fs::exists(dir / "s.json") ||
                 fs::exists(dir / "fit"));
  }
  // A frame with 10% of its pixels valid passes the floor (the mask runs).
  capture::LatLongFrame f = capture::ReadLatLongFrame(sky);
  for (size_t i = 0; i < f.radiance.pixels.size(); ++i) {
    if ((i / 3) % 10 != 0) f.radiance.pixels[i] = std::numeric_limits<float>::quiet_NaN();
  }
  capture::WriteLatLongFrame(dir / "sparse.exr", f);
  const ProcessResult ok = Skycal("import --in " + (dir / "sparse.exr") + " --out " + (dir / "i.exr"));
  EXPECT_EQ(ok.rc, 0) << ok.err;
}

TEST(Reliability, PathMessagesSayWhatIsThere) {
  ScratchDir dir("rel-messages");
  fs::create_directory(dir.path() / "adir");
  ASSERT_EQ(::mkfifo((dir / "fifo.exr").c_str(), 0600), 0);
  fs::create_symlink("loop_b.exr", dir.path() / "loop_a.exr");
  fs::create_symlink("loop_a.exr", dir.path() / "loop_b.exr");
  fs::create_symlink("nowhere.exr", dir.path() / "dangling.exr");
  testing::WriteText(dir / "file.txt", "x");
  for (const auto& [in, says] : {std::pair{std::string("adir"), std::string("is a directory")},
                                 std::pair{std::string("fifo.exr"), std::string("not a regular file")},
                                 std::pair{std::string("loop_a.exr"), std::string("symlink loop")},
                                 std::pair{std::string("dangling.exr"), std::string("dangling symlink")},
                                 std::pair{std::string("missing.exr"), std::string("no such file")}}) {
    const ProcessResult r = Skycal("probe-extract --image " + (dir / in) + " --out " + (dir / "s.json"));
    EXPECT_EQ(r.rc, 1);
    EXPECT_TRUE(Has(r.err, says)) << in << ": " << r.err;
  }
  const ProcessResult r = Skycal("render" + kSun + "--size 32x16 --backend cpu --out " + (dir / "file.txt/o.exr"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "is not a directory")) << r.err;
}

TEST(Reliability, BakeRefusesALutWidthBeforeTheCompute) {
  ScratchDir dir("rel-bake-width");
  const ProcessResult r = Skycal("bake --n-gamma 300 --out " + (dir / "p.json"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "--n-gamma") && Has(r.err, "[2, 256]")) << r.err;
  EXPECT_FALSE(Has(r.err, "luts.")) << "names the option, not a JSON field: " << r.err;
  EXPECT_FALSE(fs::exists(dir / "p.json"));
  EXPECT_EQ(Skycal("bake --n-gamma 256 --n-theta 8 --out " + (dir / "p.json")).rc, 0);
}

TEST(Reliability, AReportEmbedsOnlyTheRunsOwnFiles) {
  ScratchDir dir("rel-report-embed");
  const std::string sky = Render(dir, "sky.exr");
  ASSERT_EQ(Skycal("fit --quiet --backend cpu --reference " + sky + " --out " + (dir / "out")).rc, 0);
  fs::copy(dir / "out/fit/sky.reference.png", dir / "outside.png");
  const nlohmann::json original = nlohmann::json::parse(testing::Slurp(dir / "out/fit.json"));
  for (const std::string& elsewhere : {dir / "outside.png", std::string("../outside.png")}) {
    nlohmann::json j = original;
    j["references"][0]["images"]["reference"] = elsewhere;
    testing::WriteText(dir / "out/fit.json", j.dump());
    const ProcessResult r = Skycal("report " + (dir / "out") + " --out " + (dir / "r.html"));
    EXPECT_EQ(r.rc, 1) << elsewhere;
    EXPECT_TRUE(Has(r.err, "outside the fit's directory")) << r.err;
    EXPECT_FALSE(fs::exists(dir / "r.html"));
  }
  testing::WriteText(dir / "out/fit.json", original.dump());
  EXPECT_EQ(Skycal("report " + (dir / "out") + " --out " + (dir / "r.html")).rc, 0);
}

TEST(Reliability, AFitRerunKeepsTheFoldersAndLinksTheUserAdded) {
  ScratchDir dir("rel-rerun");
  const std::string sky = Render(dir, "sky.exr");
  const std::string fit = "fit --quiet --backend cpu --reference " + sky + " --out " + (dir / "out");
  ASSERT_EQ(Skycal(fit).rc, 0);
  ASSERT_EQ(Skycal(fit).rc, 0);  // its own output, untouched: replaced
  fs::create_directory(dir.path() / "out/notes");
  ProcessResult r = Skycal(fit);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "folder 'notes'")) << r.err;
  EXPECT_TRUE(fs::is_directory(dir.path() / "out/notes"));
  fs::remove(dir.path() / "out/notes");
  fs::create_directory_symlink(dir.path(), dir.path() / "out/link");
  r = Skycal(fit);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "symbolic link 'link'")) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path() / "out/link"));
  fs::remove(dir.path() / "out/link");
  EXPECT_EQ(Skycal(fit).rc, 0);
}

// An EXR whose data window is `data` inside the display window `display` (x0, y0, x1, y1).
void WriteWindowed(const std::string& path, const Imath::Box2i& display, const Imath::Box2i& data) {
  Imf::Header header(display, data);
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  const int w = data.max.x - data.min.x + 1, h = data.max.y - data.min.y + 1;
  std::vector<float> px(static_cast<size_t>(w) * h * 3, 1.0f);
  Imf::OutputFile file(path.c_str(), header);
  Imf::FrameBuffer fb;
  for (int c = 0; c < 3; ++c) {
    char* base = reinterpret_cast<char*>(px.data() + c) -
                 (static_cast<ptrdiff_t>(data.min.x) + static_cast<ptrdiff_t>(data.min.y) * w) * 3 * sizeof(float);
    fb.insert(std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, base, 3 * sizeof(float), 3 * sizeof(float) * w));
  }
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

TEST(Reliability, ExrWindowsAndOutputExtensionsAreChecked) {
  ScratchDir dir("rel-headers");
  const Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(63, 31));
  WriteWindowed(dir / "crop.exr", display, Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(31, 31)));
  WriteWindowed(dir / "offset.exr", display, Imath::Box2i(Imath::V2i(8, 0), Imath::V2i(71, 31)));
  for (const auto& [file, box] : {std::pair{std::string("crop.exr"), std::string("(0, 0) - (31, 31)")},
                                  std::pair{std::string("offset.exr"), std::string("(8, 0) - (71, 31)")}}) {
    for (const auto& [verb, out] : {std::pair{std::string("probe-extract --image "), std::string("o.json")},
                                    std::pair{std::string("resample --in "), std::string("o.exr")},
                                    std::pair{std::string("import --in "), std::string("o.exr")}}) {
      const ProcessResult r = Skycal(verb + (dir / file) + " --out " + (dir / out));
      EXPECT_EQ(r.rc, 1) << verb << file;
      EXPECT_TRUE(Has(r.err, file) && Has(r.err, box) && Has(r.err, "(0, 0) - (63, 31)")) << r.err;
    }
  }
  const ProcessResult w = Skycal("weather --size 16 --out " + (dir / "w.png"));
  EXPECT_EQ(w.rc, 1);
  EXPECT_TRUE(Has(w.err, "ending in .exr")) << w.err;
  EXPECT_FALSE(fs::exists(dir / "w.png"));
  EXPECT_EQ(Skycal("weather --size 16 --out " + (dir / "w.exr")).rc, 0);
}

}  // namespace
}  // namespace skycal
