// The HTML report's pieces and its bad input: escaping (HTML injection from a name read from
// a file), base64 (RFC 4648's vectors), and missing or malformed inputs (clear errors naming
// the file and the field, exit 1, nothing written). The page itself in a browser:
// tests/report_browser_test.cc.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/report/html.h"
#include "skycal/report/report.h"
#include "test_util.h"

namespace skycal {
namespace {

namespace fs = std::filesystem;
using testing::ScratchDir;
using testing::WriteText;

TEST(ReportHtml, EscapesMarkupAndBadUtf8) {
  EXPECT_EQ(report::EscapeHtml("<img src=x onerror=\"a('b')\">&"),
            "&lt;img src=x onerror=&quot;a(&#39;b&#39;)&quot;&gt;&amp;");
  EXPECT_EQ(report::EscapeHtml("K\xC3\xB6ln \xE2\x80\x93 ok"), "K\xC3\xB6ln \xE2\x80\x93 ok");  // valid UTF-8 kept
  EXPECT_EQ(report::EscapeHtml("a\xFF" "b"), "a\xEF\xBF\xBD" "b");                               // invalid byte
  EXPECT_EQ(report::EscapeHtml("\xC0\xAF"), "\xEF\xBF\xBD\xEF\xBF\xBD");                          // overlong '/'
  EXPECT_EQ(report::EscapeHtml("\xED\xA0\x80"), "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD");          // a surrogate
}

TEST(ReportHtml, Base64MatchesRfc4648AndRoundTrips) {
  const std::pair<const char*, const char*> vectors[] = {{"", ""},         {"f", "Zg=="},         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},  {"foob", "Zm9vYg=="}, {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, coded] : vectors) {
    EXPECT_EQ(report::Base64Encode(plain), coded);
    EXPECT_EQ(report::Base64Decode(coded), plain);
  }
  std::string bytes;
  for (int i = 0; i < 256; ++i) bytes += static_cast<char>(i);
  EXPECT_EQ(report::Base64Decode(report::Base64Encode(bytes)), bytes);
  EXPECT_THROW(report::Base64Decode("Zm9v*mFy"), Error);
  EXPECT_THROW(report::Base64Decode("Z"), Error);
  EXPECT_EQ(report::DataUri("image/png", "fo"), "data:image/png;base64,Zm8=");
}

// A minimal fit directory as `skycal fit` writes it (no images: the report says so).
void WriteMinimalFit(const fs::path& dir, const nlohmann::json& reference) {
  fs::create_directories(dir);
  const nlohmann::json fit = {{"haziness_g", 0.8},
                              {"references", nlohmann::json::array({reference})},
                              {"levels", nlohmann::json::array()},
                              {"decisions", nlohmann::json::array()}};
  WriteText((dir / "fit.json").string(), fit.dump());
}

std::string ErrorOf(const std::string& dir, const report::ReportOptions& o = {}) {
  try {
    report::WriteReport(dir, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ReportInput, BadInputNamesFileAndFieldAndWritesNothing) {
  ScratchDir s("report_input");
  // Nothing to report on.
  EXPECT_NE(ErrorOf(s / "absent").find("not a directory"), std::string::npos);
  fs::create_directories(s / "empty");
  EXPECT_NE(ErrorOf(s / "empty").find("no fit.json (skycal fit), manifest.json"), std::string::npos);
  // Not JSON.
  fs::create_directories(s / "corrupt");
  WriteText(s / "corrupt/fit.json", "{\"haziness_g\": 0.8, \"references\": [");
  std::string e = ErrorOf(s / "corrupt");
  EXPECT_NE(e.find("corrupt/fit.json"), std::string::npos) << e;
  // A field missing, and one of the wrong type.
  WriteMinimalFit(s.path() / "missing", {{"name", "noon"}, {"log_rmse", 0.01}});
  e = ErrorOf(s / "missing");
  EXPECT_NE(e.find("missing/fit.json: field 'references[0].rel_rmse': missing"), std::string::npos) << e;
  WriteMinimalFit(s.path() / "typed", {{"name", "noon"}, {"rel_rmse", "2%"}, {"log_rmse", 0.01}});
  e = ErrorOf(s / "typed");
  EXPECT_NE(e.find("typed/fit.json: field 'references[0].rel_rmse': expected a number, found string"), std::string::npos) << e;
  // An image fit.json lists but that is not there.
  WriteMinimalFit(s.path() / "noimage", {{"name", "noon"}, {"rel_rmse", 0.01}, {"log_rmse", 0.01},
                                         {"images", {{"reference", "fit/noon.reference.png"}, {"fit", "x"}, {"error", "y"}}}});
  e = ErrorOf(s / "noimage");
  EXPECT_NE(e.find("field 'references[0].images.reference': the image"), std::string::npos) << e;
  // A PNG that is not one.
  WriteMinimalFit(s.path() / "badpng", {{"name", "noon"}, {"rel_rmse", 0.01}, {"log_rmse", 0.01}});
  fs::create_directories(s.path() / "badpng/fit");
  for (const char* k : {"reference", "fit", "error"}) WriteText(s / ("badpng/fit/noon." + std::string(k) + ".png"), "GIF89a");
  e = ErrorOf(s / "badpng");
  EXPECT_NE(e.find("noon.reference.png: not a PNG file"), std::string::npos) << e;
  for (const char* d : {"corrupt", "missing", "typed", "noimage", "badpng"}) {
    EXPECT_FALSE(fs::exists(s.path() / d / "report.html")) << d;
    for (const auto& f : fs::directory_iterator(s.path() / d)) {
      EXPECT_EQ(f.path().filename().string().find(".tmp-"), std::string::npos) << f.path();  // no temporary left
    }
  }
  // The output may not replace an input.
  WriteMinimalFit(s.path() / "ok", {{"name", "noon"}, {"rel_rmse", 0.01}, {"log_rmse", 0.01}});
  report::ReportOptions over;
  over.out_path = s / "ok/fit.json";
  e = ErrorOf(s / "ok", over);
  EXPECT_NE(e.find("fit.json"), std::string::npos) << e;
  EXPECT_EQ(nlohmann::json::parse(testing::Slurp(s / "ok/fit.json"))["haziness_g"], 0.8);  // untouched
  // The control: the same directory with a valid output path works.
  const report::ReportSummary ok = report::WriteReport(s / "ok", {});
  EXPECT_EQ(ok.fits, 1);
  EXPECT_TRUE(fs::exists(s.path() / "ok/report.html"));
}

// A time-lapse day of many fits: each is in the day's table, a few in full.
TEST(ReportInput, ALongDayShowsEvenlySpacedFitsInFull) {
  ScratchDir s("report_longday");
  for (int i = 0; i < 30; ++i) {
    const fs::path dir = s.path() / ("frame_" + std::to_string(100 + i));
    WriteMinimalFit(dir, {{"name", "f" + std::to_string(i)}, {"rel_rmse", 0.01 + 0.001 * i}, {"log_rmse", 0.01}});
    nlohmann::json j = nlohmann::json::parse(testing::Slurp((dir / "fit.json").string()));
    j["time_of_day_h"] = 23.5 - 0.75 * i;  // directory order is the reverse of time order
    WriteText((dir / "fit.json").string(), j.dump());
  }
  report::ReportOptions o;
  o.max_fit_sections = 5;
  const report::ReportSummary sum = report::WriteReport(s.path().string(), o);
  EXPECT_EQ(sum.fits, 30);
  EXPECT_EQ(sum.frames, 30);
  EXPECT_EQ(sum.fit_sections, 5);
  EXPECT_TRUE(sum.day);
  const std::string html = testing::Slurp(s / "report.html");
  EXPECT_NE(html.find("5 of 30 fits are shown in full"), std::string::npos);
  // Sorted by time: the first section is the earliest frame (the last directory), the last the latest.
  EXPECT_LT(html.find("<h2>Fit: frame_129</h2>"), html.find("<h2>Fit: frame_100</h2>"));
  EXPECT_EQ(html.find("<h2>Fit: frame_128</h2>"), std::string::npos);  // not one of the 5
  report::ReportOptions bad;
  bad.max_fit_sections = 0;
  EXPECT_NE(ErrorOf(s.path().string(), bad).find("max_fit_sections"), std::string::npos);
}

TEST(ReportInput, NamesFromFilesAreEscaped) {
  ScratchDir s("report_escape");
  const std::string hostile = "<img src=x onerror=alert(1)>\"'&";
  WriteMinimalFit(s.path() / "fit", {{"name", hostile}, {"rel_rmse", 0.01}, {"log_rmse", 0.01}});
  report::WriteReport(s / "fit", {});
  const std::string html = testing::Slurp(s / "fit/report.html");
  EXPECT_EQ(html.find(hostile), std::string::npos);
  EXPECT_EQ(html.find("<img src=x"), std::string::npos);
  EXPECT_NE(html.find("&lt;img src=x onerror=alert(1)&gt;&quot;&#39;&amp;"), std::string::npos);
}

TEST(ReportCli, ExitCodeAndMessageThroughTheBinary) {
  ScratchDir s("report_cli");
  fs::create_directories(s / "bad");
  WriteText(s / "bad/fit.json", "[1, 2]");
  const auto r = testing::RunSkycal(SKYCAL_BINARY, "report " + (s / "bad"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("bad/fit.json: expected a JSON object"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(s / "bad/report.html"));
  const auto usage = testing::RunSkycal(SKYCAL_BINARY, "report");
  EXPECT_EQ(usage.rc, 1);
  EXPECT_NE(usage.err.find("expected the directory to report on"), std::string::npos) << usage.err;
  const auto depth = testing::RunSkycal(SKYCAL_BINARY, "report " + (s / "bad") + " --depth 99");
  EXPECT_EQ(depth.rc, 1);
  EXPECT_NE(depth.err.find("--depth"), std::string::npos) << depth.err;
}

// What the report's convergence curve is drawn from: fit.json's costs per Ceres iteration
// (Ceres' own initial and final cost at the ends, never rising: an unsuccessful step keeps
// the cost) and per Gauss-Newton step of the linear start (one per step it counts).
TEST(ReportFitJson, CarriesTheConvergenceCurve) {
  ScratchDir s("report_fitjson");
  auto r = testing::RunSkycal(SKYCAL_BINARY, "render --size 256x128 --sun-elevation 30 --sun-azimuth 10 --backend cpu --out " +
                                                 (s / "sky.exr"));
  ASSERT_EQ(r.rc, 0) << r.err;
  r = testing::RunSkycal(SKYCAL_BINARY, "fit --quiet --polish --backend cpu --no-report --reference " + (s / "sky.exr") +
                                            " --out " + (s / "fit"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(fs::exists(s.path() / "fit/report.html"));  // --no-report
  const nlohmann::json j = nlohmann::json::parse(testing::Slurp(s / "fit/fit.json"));
  ASSERT_FALSE(j["levels"].empty());
  for (const auto& l : j["levels"]) {
    const std::vector<double> c = l["cost_per_iteration"];
    ASSERT_EQ(c.size(), l["iterations"].get<size_t>() + 1);
    EXPECT_DOUBLE_EQ(c.front(), l["initial_cost"].get<double>());
    EXPECT_DOUBLE_EQ(c.back(), l["final_cost"].get<double>());
    for (size_t i = 1; i < c.size(); ++i) EXPECT_LE(c[i], c[i - 1]) << "iteration " << i;
  }
  const auto& steps = j["linear_start"]["cost_per_step"];
  ASSERT_EQ(steps.size(), j["linear_start"]["gauss_newton_steps"].get<size_t>());
  for (const auto& st : steps) {
    EXPECT_GT(st["cost"].get<double>(), 0.0);
    EXPECT_TRUE(st["width"] == 128 || st["width"] == 256) << st.dump();
  }
  const auto& ref = j["references"][0];
  EXPECT_EQ(ref["images"]["error"], "fit/sky.error.png");
  for (const char* k : {"reference", "fit", "error"}) EXPECT_TRUE(fs::exists(s.path() / "fit" / ref["images"][k].get<std::string>()));
  // The sun at the ground: the bundled preset's 128 klux x transmittance, well below it at 30 deg.
  EXPECT_GT(ref["sun_illuminance_at_ground_lux"].get<double>(), 1e4);
  EXPECT_LT(ref["sun_illuminance_at_ground_lux"].get<double>(), 1.28e5);
}

// fit --cloud-mask on a clear render (nothing is cloud) and on the same sky with a grey
// "cloud" painted over 80x20 pixels above the horizon (the mask must take it out).
TEST(ReportFitJson, CloudMaskLeavesOutThePaintedCloudOnly) {
  ScratchDir s("report_cloudmask");
  auto r = testing::RunSkycal(SKYCAL_BINARY, "render --size 256x128 --sun-elevation 35 --sun-azimuth 60 --backend cpu --out " +
                                                 (s / "clear.exr"));
  ASSERT_EQ(r.rc, 0) << r.err;
  ExrRGB sky = ReadExrRGB(s / "clear.exr");
  const int w = sky.image.width;
  const int x0 = 150, y0 = 20, pw = 80, ph = 20;  // sun at azimuth 60: column ~85, well away
  for (int y = y0; y < y0 + ph; ++y) {
    for (int x = x0; x < x0 + pw; ++x) {
      float* p = &sky.image.pixels[3 * (static_cast<size_t>(y) * w + x)];
      const float grey = 0.9f * (p[0] + p[1] + p[2]);  // white-grey, a little brighter than the sky
      p[0] = p[1] = p[2] = grey;
    }
  }
  WriteExrRGB(s / "cloudy.exr", sky.image, sky.attributes);
  long long cloudy[2] = {0, 0};
  double fraction[2] = {0, 0};
  int k = 0;
  for (const char* name : {"clear", "cloudy"}) {
    r = testing::RunSkycal(SKYCAL_BINARY, std::string("fit --quiet --no-report --backend cpu --cloud-mask --reference ") +
                                              (s / (std::string(name) + ".exr")) + " --out " + (s / (std::string("fit_") + name)));
    ASSERT_EQ(r.rc, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(testing::Slurp(s / (std::string("fit_") + name + "/fit.json")));
    cloudy[k] = j["references"][0]["cloud_mask"]["cloudy_pixels"];
    fraction[k] = j["references"][0]["cloud_mask"]["fraction"];
    EXPECT_EQ(j["references"][0]["pixels"]["user_masked"].get<long long>(), cloudy[k]);
    ++k;
  }
  EXPECT_LT(fraction[0], 0.01) << "a clear render of the preset the mask expects has no cloud";
  EXPECT_GE(cloudy[1], cloudy[0] + static_cast<long long>(0.9 * pw * ph));
  EXPECT_LE(cloudy[1], cloudy[0] + static_cast<long long>(1.2 * pw * ph));
}

// fit --clouds: the fit's `clouds` object becomes a table per fit (value, initial, unit, held and
// why); a held parameter's reason is shown (escaped); a wrongly typed field is named.
TEST(ReportInput, CloudLightingTableFromFitJson) {
  ScratchDir s("report_clouds");
  WriteMinimalFit(s.path() / "fit", {{"name", "noon"}, {"rel_rmse", 0.01}, {"log_rmse", 0.01}});
  nlohmann::json j = nlohmann::json::parse(testing::Slurp((s / "fit/fit.json")));
  j["clouds"] = {{"fitted", true},
                 {"decision", "--clouds on: 656 of 4094 fitted sky pixels are cloud"},
                 {"cloud_pixels", {{"initial", {{"log_rmse", 0.25}}}, {"final", {{"log_rmse", 0.125}}}}},
                 {"parameters",
                  {{"extinction", {{"value", 0.0625}, {"unit", "1/m"}, {"initial", 0.05}, {"held", false}}},
                   {"powder_strength", {{"value", 0.4}, {"unit", "1"}, {"initial", 0.4}, {"held", true},
                                        {"why", "inseparable: collinear with <extinction>"}}}}}};
  WriteText((s / "fit/fit.json"), j.dump());
  report::WriteReport(s / "fit", {});
  const std::string html = testing::Slurp(s / "fit/report.html");
  EXPECT_NE(html.find("Cloud lighting (fit --clouds)"), std::string::npos);
  EXPECT_NE(html.find("<td>extinction</td><td>0.0625</td><td>0.05</td><td>1/m</td><td>fitted</td>"), std::string::npos);
  EXPECT_NE(html.find("collinear with &lt;extinction&gt;"), std::string::npos);
  EXPECT_NE(html.find("log RMSE 0.25 at the start, 0.125 fitted"), std::string::npos);
  // A day of two such fits: the cloud lighting over the day is plotted (fitted / start).
  fs::create_directories(s / "day");
  for (int k = 0; k < 2; ++k) {
    const fs::path d = s.path() / "day" / ("frame" + std::to_string(k));
    WriteMinimalFit(d, {{"name", "f" + std::to_string(k)}, {"rel_rmse", 0.01}, {"log_rmse", 0.01}});
    nlohmann::json dj = j;
    dj["time_of_day_h"] = 9.0 + k;
    dj["references"] = nlohmann::json::parse(testing::Slurp((d / "fit.json").string()))["references"];
    WriteText((d / "fit.json").string(), dj.dump());
  }
  report::WriteReport(s / "day", {});
  const std::string day = testing::Slurp(s / "day/report.html");
  EXPECT_NE(day.find("alt=\"cloud lighting (fit --clouds): fitted value / start value\""), std::string::npos);
  j["clouds"]["parameters"]["extinction"]["value"] = "fast";
  WriteText((s / "fit/fit.json"), j.dump());
  EXPECT_NE(ErrorOf(s / "fit").find("clouds.parameters.extinction.value"), std::string::npos) << ErrorOf(s / "fit");
}

// fit --clouds stats (photographs): fit.json's cloud_stats gives the parameter table and,
// per reference, the panels and the whole-sky errors without and with the statistics.
TEST(ReportInput, CloudStatisticsOfAPhotoFromFitJson) {
  ScratchDir s("report_cloud_stats");
  WriteMinimalFit(s.path() / "fit", {{"name", "sky"}, {"rel_rmse", 0.17}, {"log_rmse", 0.2}});
  fs::create_directories(s.path() / "fit/fit");
  // A 1x1 RGB PNG (its bytes written out: the report only embeds them).
  const std::string png("\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x01\x00\x00\x00\x01\x08\x02"
                        "\x00\x00\x00\x90\x77\x53\xde\x00\x00\x00\x0c\x49\x44\x41\x54\x78\x9c\x63\x68\x68\x68\x00\x00\x03\x04"
                        "\x01\x81\x4b\xd3\xd2\x10\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
                        69);
  for (const char* k : {"reference", "fit", "error"}) WriteText(s / ("fit/fit/sky.clouds." + std::string(k) + ".png"), png);
  nlohmann::json j = nlohmann::json::parse(testing::Slurp(s / "fit/fit.json"));
  auto errors = [](double rel, double log) { return nlohmann::json{{"whole_sky", {{"rel_rmse", rel}, {"log_rmse", log}}}}; };
  j["clouds"] = {{"mode", "stats"}, {"decision", "--clouds stats: the cloud lighting by statistics"}};
  j["cloud_stats"] = {
      {"parameters",
       {{"scattering_albedo", {{"value", 0.987}, {"unit", "1"}, {"initial", 1.0}, {"held", false}}},
        {"phase_g1", {{"value", 0.5}, {"unit", "1"}, {"initial", 0.5}, {"held", true}, {"why", "not recoverable"}}}}},
      {"references",
       {{{"name", "sky"},
         {"errors", {{"atmosphere_only", errors(0.337, 0.35)}, {"with_cloud_statistics", errors(0.278, 0.298)}}},
         {"images",
          {{"reference", "fit/sky.clouds.reference.png"}, {"fit", "fit/sky.clouds.fit.png"}, {"error", "fit/sky.clouds.error.png"}}}}}}};
  WriteText(s / "fit/fit.json", j.dump());
  report::WriteReport(s / "fit", {});
  const std::string html = testing::Slurp(s / "fit/report.html");
  EXPECT_NE(html.find("<td>scattering_albedo</td><td>0.987</td><td>1</td><td>1</td><td>fitted</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>phase_g1</td><td>0.5</td><td>0.5</td><td>1</td><td>not recoverable</td>"), std::string::npos);
  EXPECT_NE(html.find("Cloud statistics of sky (fit --clouds stats)"), std::string::npos);
  EXPECT_NE(html.find("33.7% rel RMSE, 0.35 log RMSE"), std::string::npos);
  EXPECT_NE(html.find("27.8% rel RMSE, 0.298 log RMSE"), std::string::npos);
  EXPECT_NE(html.find("alt=\"cloud statistics fit of sky\""), std::string::npos);
  // A panel fit.json lists but that is not there: named by its field.
  fs::remove(s.path() / "fit/fit/sky.clouds.error.png");
  fs::remove(s.path() / "fit/report.html");
  const std::string e = ErrorOf(s / "fit");
  EXPECT_NE(e.find("cloud_stats.references[0].images.error"), std::string::npos) << e;
}

TEST(ReportOptions, IsValidNamesTheFieldAndItsValue) {
  report::ReportOptions o;
  o.max_depth = 9;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ReportOptions::max_depth = 9 (expected directory levels searched below DIR in [0, 8])");
}

}  // namespace
}  // namespace skycal
