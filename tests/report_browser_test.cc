// The report in a real browser: a day of three fits (one reference named like an HTML
// injection), their export and a bench output, through `skycal fit / export / report`, loaded
// by headless Chromium: no console error, every image decodes, every plot has ink where it
// sits on the screenshot, no element came from a file name. The screenshot and the page are
// kept in the build tree (the path is printed). A control page proves each check can fail.
// Skips only where Chromium cannot run (not installed, or it cannot start here).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "browser_page.h"
#include "run_binary.h"
#include "skycal/report/html.h"
#include "skycal/report/report.h"

namespace skycal {
namespace {

namespace fs = std::filesystem;

const fs::path kOut = fs::path(SKYCAL_TEST_OUTPUT_DIR);

std::string Q(const fs::path& p) { return "'" + p.string() + "'"; }

void RunOk(const std::string& args) {
  const auto r = testing::RunSkycal(SKYCAL_BINARY, args);
  ASSERT_EQ(r.rc, 0) << "skycal " << args << "\n" << r.err;
}

void WriteBytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

TEST(ReportBrowser, DayExportAndBenchRenderInChromium) {
  const fs::path day = kOut / "day";
  // Only this test's outputs: the control test below writes beside them, and CTest may run
  // the two at once (removing the whole folder took the control page from under Chromium).
  for (const char* own : {"day", "report.html", "report_screenshot.png", "chromium-profile"}) fs::remove_all(kOut / own);
  fs::create_directories(day);
  // Three frames of a day, 256x128 renders of the bundled preset (the fits recover them).
  const std::string hostile = "<img src=x onerror=console.error(1)>";
  const struct {
    double hour, elevation;
    std::string name;
  } frames[] = {{7.5, 12.0, "morning"}, {12.0, 55.0, hostile}, {17.0, 20.0, "evening"}};
  int k = 0;
  for (const auto& f : frames) {
    const fs::path ref = day / (f.name + ".exr");
    RunOk("render --size 256x128 --sun-elevation " + std::to_string(f.elevation) + " --sun-azimuth 30 --out " + Q(ref));
    const fs::path fit = day / ("fit_" + std::to_string(k++));
    RunOk("fit --quiet --reference " + Q(ref) + " --time " + std::to_string(f.hour) + " --out " + Q(fit));
    ASSERT_TRUE(fs::exists(fit / "report.html")) << "fit writes its own report";
  }
  RunOk("export --preset " + Q(day / "fit_0/preset.json") + " --preset " + Q(day / "fit_1/preset.json") + " --preset " +
      Q(day / "fit_2/preset.json") + " --out " + Q(day / "game"));
  ASSERT_TRUE(fs::exists(day / "game/report.html")) << "export writes its own report";
  fs::copy(fs::path(SKYCAL_SOURCE_DIR) / "bench/results/current", day / "bench", fs::copy_options::recursive);
  const auto rep = testing::RunSkycal(SKYCAL_BINARY, "report " + Q(day) + " --out " + Q(kOut / "report.html") + " --json");
  ASSERT_EQ(rep.rc, 0) << rep.err;
  const nlohmann::json summary = nlohmann::json::parse(rep.out);
  EXPECT_EQ(summary["fits"], 3);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["exports"], 1);
  EXPECT_EQ(summary["benches"], 1);
  EXPECT_EQ(summary["day"], true);
  EXPECT_EQ(summary["images"], 3 * 3 + 5);           // reference | fit | error per frame, 5 bench plots
  EXPECT_GE(summary["plots"].get<int>(), 4 + 3 + 1);  // the day's 4, a convergence curve per fit, the keyframes

  std::string why;
  const auto page = testing::LoadPageInChromium((kOut / "report.html").string(), (kOut / "chromium-profile").string(), &why, 0.5);
  if (!page) GTEST_SKIP() << why;
  const fs::path shot = kOut / "report_screenshot.png";
  WriteBytes(shot, page->screenshot_png);
  std::cout << "[report] screenshot: " << shot.string() << " (" << page->page_width << "x" << page->page_height
            << " CSS px at scale 0.5, " << page->browser << ")\n";
  EXPECT_TRUE(page->errors.empty()) << page->errors.front();
  // Every <img> is one the report embedded (none came from the hostile name) and decodes.
  EXPECT_EQ(static_cast<int>(page->images.size()), summary["images"].get<int>() + summary["plots"].get<int>());
  int plots = 0;
  for (const testing::PageImage& im : page->images) {
    EXPECT_GT(im.natural_width, 0) << im.alt;
    EXPECT_GT(im.natural_height, 0) << im.alt;
    const double ink = testing::InkFraction(*page, im);
    // A plot: axes, grid, labels and lines are a few % of its area (measured 3-12%); a sky image
    // is mostly non-uniform. Blank is 0.
    EXPECT_GT(ink, 0.01) << im.cls << " '" << im.alt << "' at " << im.x << "," << im.y << " is blank on the screenshot";
    plots += im.cls == "plot";
  }
  EXPECT_EQ(plots, summary["plots"].get<int>() + 5);
}

TEST(ReportBrowser, ControlPageFailsEveryCheck) {
  // A broken image, a console error and a blank "plot": each check must see its fault.
  const fs::path dir = kOut / "control";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string blank_svg =
      "<svg xmlns='http://www.w3.org/2000/svg' width='400' height='200'><rect width='400' height='200' fill='white'/></svg>";
  WriteBytes(dir / "control.html",
             "<!DOCTYPE html><html><body><h1>control</h1>"
             "<img class='image' alt='broken' src='data:image/png;base64,iVBORw0KGgoAAAAN'>"
             "<img class='plot' alt='blank' style='border:1px solid #ddd' src='" +
                 report::DataUri("image/svg+xml", blank_svg) +
                 "'>"
                 "<script>console.error('control error');</script></body></html>");
  std::string why;
  const auto page = testing::LoadPageInChromium((dir / "control.html").string(), (dir / "profile").string(), &why);
  if (!page) GTEST_SKIP() << why;
  ASSERT_EQ(page->images.size(), 2u);
  EXPECT_FALSE(page->errors.empty());
  EXPECT_EQ(page->images[0].natural_width, 0);  // the truncated PNG does not decode
  EXPECT_GT(page->images[1].natural_width, 0);
  EXPECT_LT(testing::InkFraction(*page, page->images[1]), 0.001);
}

}  // namespace
}  // namespace skycal
