// Reliability through the binary: an optional plot never ends a job (PLplot without its
// drivers), a single-file output never replaces a file of another kind or a page skycal did
// not write, a preset interrupted between its files is still one whole preset, no NaN or
// inf is ever written (crafted EXRs), and EXR windows and output extensions are checked.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>

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
    EXPECT_EQ(r.rc, 128 + 15) << "SIGTERM after file " << stop_after << ": " << r.err;
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

}  // namespace
}  // namespace skycal
