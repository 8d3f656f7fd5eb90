// `skycal bench`'s plumbing (no timed assertions): grid expansion, the Pareto front on a
// hand-made set, the results files' schema, --compare's regression flag against the
// measured noise, the stress table, and bad input (unknown suite, a user's directory,
// --repeat). A fake suite with fixed numbers drives the verb end to end.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bench_verb.h"
#include "command_line.h"
#include "skycal/bench/cloud_stats_suite_grids.h"
#include "skycal/bench/compare.h"
#include "skycal/bench/last_suite_grids.h"
#include "skycal/bench/fit_suite_grids.h"
#include "skycal/bench/grid.h"
#include "skycal/bench/pareto.h"
#include "skycal/bench/results.h"
#include "skycal/bench/stress_table.h"
#include "skycal/bench/study_suite_grids.h"
#include "skycal/bench/suite.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "test_util.h"
#include "export_verb.h"
#include "skycal/controllers/probe_extract.h"
#include "skycal/core/exr_io.h"
#include "cloud_scene.h"
#include "image_compare.h"
#include "suite_util.h"
#include "render_verb.h"
#include "verb_common.h"

using namespace skycal;
using namespace skycal::bench;

namespace {

Timing T(double median, double min, double max, int runs = 5) {
  Timing t;
  t.median_ms = median;
  t.min_ms = min;
  t.max_ms = max;
  t.runs = runs;
  return t;
}

CaseResult MakeCase(const std::string& suite, const Settings& s, Timing t, double error, bool is_default = false) {
  CaseResult c;
  c.suite = suite;
  c.settings = s;
  c.name = Label(s);
  c.time = t;
  c.error = error;
  c.is_default = is_default;
  return c;
}

// A suite with fixed numbers: size x method; "fast" dominated by nothing, "slow-bad" dominated.
SuiteRegistry FakeRegistry(Outcome last_outcome = Outcome::kOk) {
  SuiteRegistry r;
  Suite s;
  s.name = "fake";
  s.summary = "fixed numbers";
  s.error_metric = "rel error";
  s.run = [last_outcome](const SuiteOptions& o) {
    Grid g;
    g.axes = {{"size", {"small", "large"}, "large"}, {"method", {"a", "b"}, "a"}};
    std::vector<CaseResult> out;
    const double times[] = {1.0, 2.0, 10.0, 20.0}, errors[] = {0.1, 0.2, 0.01, 0.02};
    int i = 0;
    for (const Settings& st : g.Expand()) {
      out.push_back(MakeCase("fake", st, T(times[i], times[i] * 0.9, times[i] * 1.1), errors[i], st == g.Defaults()));
      ++i;
    }
    out.back().outcome = last_outcome;
    for (const CaseResult& c : out) o.Done(c);
    return out;
  };
  s.markdown = [](const std::vector<CaseResult>& cases) { return "# fake\n" + std::to_string(cases.size()) + " cases\n"; };
  r.Add(s);
  return r;
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

TEST(BenchGrid, ExpandsTheProductInAxisOrder) {
  Grid g;
  g.axes = {{"backend", {"vulkan", "cpu"}, "vulkan"}, {"size", {"256", "512", "1024"}, "1024"}};
  const std::vector<Settings> pts = g.Expand();
  ASSERT_EQ(pts.size(), 6u);
  EXPECT_EQ(Label(pts[0]), "backend=vulkan size=256");
  EXPECT_EQ(Label(pts[1]), "backend=vulkan size=512");
  EXPECT_EQ(Label(pts[3]), "backend=cpu size=256");
  EXPECT_EQ(Label(pts[5]), "backend=cpu size=1024");
  EXPECT_EQ(Label(g.Defaults()), "backend=vulkan size=1024");
  EXPECT_EQ(Get(pts[4], "size"), "512");
  EXPECT_THROW(Get(pts[4], "loss"), Error);
}

TEST(BenchGrid, SkipDropsPointsAndBadGridsThrow) {
  Grid g;
  g.axes = {{"linear_start", {"on", "off"}, "on"}, {"loss", {"cauchy", "huber", "none"}, "cauchy"},
            {"jacobian", {"analytic", "numeric"}, "analytic"}};
  g.skip = [](const Settings& s) -> std::string {
    return Get(s, "jacobian") == "numeric" && (Get(s, "linear_start") == "on" || Get(s, "loss") != "cauchy") ? "no effect" : "";
  };
  const std::vector<Settings> pts = g.Expand();
  ASSERT_EQ(pts.size(), 7u);  // 6 analytic + 1 numeric (off, cauchy)
  int numeric = 0;
  for (const Settings& s : pts) numeric += Get(s, "jacobian") == "numeric";
  EXPECT_EQ(numeric, 1);
  Grid bad;
  bad.axes = {{"x", {"1", "2"}, "3"}};
  EXPECT_THROW(bad.Expand(), Error);
  bad.axes = {{"x", {}, ""}};
  EXPECT_THROW(bad.Expand(), Error);
  bad.axes = {{"x", {"1"}, "1"}, {"x", {"2"}, "2"}};
  EXPECT_THROW(bad.Expand(), Error);
}

// The fit-probe and fit-clouds suites' grids (no fit run): how many cases, which is the
// default, and that each sweep stays where its skip rule puts it.
static int Count(const std::vector<Settings>& pts, const std::function<bool(const Settings&)>& pred) {
  int n = 0;
  for (const Settings& s : pts) n += pred(s);
  return n;
}

TEST(BenchFitSuites, ProbeGridSweepsWeightsAndScenariosAtTheDefaultsOnly) {
  for (const bool quick : {false, true}) {
    const Grid g = FitProbeGrid(quick);
    const std::vector<Settings> pts = g.Expand();
    const std::string small = quick ? "128x64" : "256x128";
    const int weights = quick ? 2 : 4;
    // Probe on: weights x 3 scenarios at vulkan/small, + vulkan/large, + cpu at both sizes;
    // probe off: both backends x both sizes.
    EXPECT_EQ(pts.size(), static_cast<size_t>(weights * 3 + 1 + 2 + 4)) << quick;
    EXPECT_EQ(Label(g.Defaults()), "probe=on backend=vulkan size=" + small + " probe_weight=0.1 scenario=consistent");
    EXPECT_EQ(Count(pts, [](const Settings& s) { return Get(s, "probe") == "off" &&
                                                        (Get(s, "probe_weight") != "0.1" || Get(s, "scenario") != "consistent"); }),
              0);
    EXPECT_EQ(Count(pts, [&](const Settings& s) {
                return Get(s, "probe_weight") != "0.1" && (Get(s, "backend") != "vulkan" || Get(s, "size") != small);
              }),
              0);
    EXPECT_EQ(Count(pts, [](const Settings& s) { return Get(s, "scenario") == "ground-held-low"; }), weights);
    EXPECT_EQ(Count(pts, [&](const Settings& s) { return s == g.Defaults(); }), 1);
  }
}

TEST(BenchFitSuites, CloudsGridMeasuresTheTruthStartAndTheCpuAtTheDefaultsOnly) {
  const Grid full = FitCloudsGrid(false);
  const std::vector<Settings> pts = full.Expand();
  ASSERT_EQ(pts.size(), 8u);  // bundled/vulkan: 2 sizes x 3 sample counts; bundled/cpu; truth/vulkan
  EXPECT_EQ(Label(full.Defaults()), "sky_start=bundled backend=vulkan size=256x128 samples=256");
  EXPECT_EQ(Label(pts.back()), "sky_start=truth backend=vulkan size=256x128 samples=256");
  EXPECT_EQ(Count(pts, [](const Settings& s) { return Get(s, "backend") == "cpu"; }), 1);
  const Grid quick = FitCloudsGrid(true);
  EXPECT_EQ(quick.Expand().size(), 4u);  // one size: bundled/vulkan x 2 sample counts, cpu, truth
  EXPECT_EQ(Label(quick.Defaults()), "sky_start=bundled backend=vulkan size=128x64 samples=256");
}

TEST(BenchFitSuites, RegisteredWithTheirMetrics) {
  const SuiteRegistry r = BuiltinSuites();
  for (const char* name : {"fit-probe", "fit-clouds"}) {
    const Suite* s = r.Find(name);
    ASSERT_NE(s, nullptr) << name;
    EXPECT_TRUE(s->pareto) << name;
    EXPECT_FALSE(s->error_metric.empty()) << name;
    EXPECT_FALSE(s->error_axis.empty()) << name;
  }
  EXPECT_EQ(r.Resolve("fit,fit-probe,fit-clouds").size(), 3u);
  // capture-response: its error is a multiple of the known-response merge, its tables in
  // DIR/capture-response.md; no Pareto front (the known merge is the floor, not a choice).
  const Suite* response = r.Find("capture-response");
  ASSERT_NE(response, nullptr);
  EXPECT_FALSE(response->pareto);
  EXPECT_FALSE(response->error_metric.empty());
  EXPECT_TRUE(static_cast<bool>(response->markdown));
}

// Runs `run(false)` (verbose off: nothing on stderr) and `run(true)` (the control: a user's
// run prints `loud_marker`).
static void ExpectQuietThenLoud(const std::function<void(bool verbose)>& run, const std::string& loud_marker) {
  ::testing::internal::CaptureStderr();
  run(false);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  ::testing::internal::CaptureStderr();
  run(true);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find(loud_marker), std::string::npos);
}

// The bench runs the verbs quietly: `skycal export` with verbose off prints nothing on
// stderr; on (a user's run, the control) it prints its progress lines.
TEST(BenchVerbLogs, ExportIsQuietWithVerboseOff) {
  skycal::testing::ScratchDir dir("bench-verb-logs");
  cli::ExportOptions eo;
  eo.presets = {cli::DefaultPresetPath()};
  eo.backend = render::Backend::kCpu;
  eo.report = false;
  eo.verbose = false;
  eo.out_dir = dir / "quiet";
  ::testing::internal::CaptureStderr();
  cli::RunExportImpl(eo);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  eo.verbose = true;
  eo.out_dir = dir / "loud";
  ::testing::internal::CaptureStderr();
  cli::RunExportImpl(eo);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("[export] wrote"), std::string::npos);
}

// `skycal probe-extract` (run by the stress suite) with verbose off prints nothing; on (the
// control) its one progress line.
TEST(BenchVerbLogs, ProbeExtractIsQuietWithVerboseOff) {
  skycal::testing::ScratchDir dir("bench-verb-logs-probe");
  ImageRGB im(64, 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const double dx = (x - 32) / 20.0, dy = (y - 32) / 20.0;
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = dx * dx + dy * dy < 1.0 ? static_cast<float>(0.2 + 0.8 * std::max(0.0, -dy)) : 0.05f;
    }
  controllers::ProbeExtractOptions po;
  po.image = dir / "ball.exr";
  WriteExrRGB(po.image, im, {});
  po.circle = capture::BallCircle{32, 32, 20};
  ExpectQuietThenLoud(
      [&](bool verbose) {
        po.verbose = verbose;
        po.out = dir / (verbose ? "loud.json" : "quiet.json");
        controllers::ExtractProbe(po);
      },
      "[probe-extract]");
}

// `skycal render` (the fit-clouds suite renders its reference with it) with verbose off
// prints nothing; on (the control) its backend and `wrote` lines.
TEST(BenchVerbLogs, RenderIsQuietWithVerboseOff) {
  skycal::testing::ScratchDir dir("bench-verb-logs-render");
  cli::RenderOptions ro;
  ro.backend = render::Backend::kCpu;
  ro.width = 64;
  ro.height = 32;
  ro.sun_elevation_deg = 30.0;
  ro.sun_azimuth_deg = 0.0;
  ExpectQuietThenLoud(
      [&](bool verbose) {
        ro.verbose = verbose;
        ro.out_exr = dir / (verbose ? "loud.exr" : "quiet.exr");
        cli::RunRenderImpl(ro);
      },
      "[render] wrote");
}

// The suites that replaced bench_cie, bench_sky_segmentation and bench_chart_stars: their
// grids (no fit, mask or chart run), registration and plot flags.
TEST(BenchStudySuites, GridsAndRegistration) {
  const CieStudyPlan cie = FitCieStudyPlan(false);
  ASSERT_EQ(cie.grid.Expand().size(), 3u);
  EXPECT_EQ(Label(cie.grid.Defaults()), "model=ffxv-iso");
  EXPECT_EQ(cie.types.size(), 15u);
  EXPECT_EQ(cie.elevations_deg, (std::vector<double>{10.0, 30.0, 60.0}));
  EXPECT_EQ(cie.width, 256);
  const CieStudyPlan cie_quick = FitCieStudyPlan(true);
  EXPECT_EQ(cie_quick.types, (std::vector<int>{1, 4, 7, 10, 13}));
  EXPECT_EQ(cie_quick.elevations_deg, (std::vector<double>{30.0}));

  for (const bool quick : {false, true}) {
    const SkySegmentationPlan seg = SkySegmentationGridPlan(quick);
    EXPECT_EQ(Label(seg.grid.Defaults()), "grabcut=on");
    EXPECT_EQ(seg.grid.Expand().size(), 2u);
    ASSERT_EQ(seg.frames.size(), seg.hand_masks.size());
    EXPECT_EQ(seg.frames.size(), quick ? 2u : 5u);
    int scored = 0;
    for (const std::string& m : seg.hand_masks) scored += !m.empty();
    EXPECT_EQ(scored, 2);  // sunrise and sunset: the error's IoU is over these
  }

  EXPECT_EQ(CaptureChartGrid(false).Expand().size(), 12u);  // 3 frames x 4 casts
  EXPECT_EQ(CaptureChartGrid(true).Expand().size(), 2u);
  EXPECT_EQ(Label(CaptureChartGrid(false).Defaults()), "frame=sky cast=crosstalk-warm-wb");
  for (const Settings& st : CaptureChartGrid(false).Expand()) {
    int found = 0;
    for (const ChartCast& c : ChartCasts()) found += c.name == Get(st, "cast");
    EXPECT_EQ(found, 1) << Label(st);
  }
  const std::vector<Settings> stars = CaptureStarsGrid(false).Expand();
  ASSERT_EQ(stars.size(), 7u);  // 6 bands of peak excess + the real night sky
  EXPECT_EQ(Get(stars.back(), "scene"), "night");
  EXPECT_EQ(CaptureStarsGrid(true).Expand().size(), 2u);

  const SuiteRegistry r = BuiltinSuites();
  for (const char* name : {"fit-cie-study", "sky-segmentation", "capture-chart", "capture-stars"}) {
    const Suite* s = r.Find(name);
    ASSERT_NE(s, nullptr) << name;
    EXPECT_TRUE(static_cast<bool>(s->markdown)) << name;
    EXPECT_FALSE(s->error_metric.empty()) << name;
    // A time/error trade-off only where a setting is swept (model; grabcut); the chart
    // and star suites run one setting on several inputs.
    EXPECT_EQ(s->pareto, std::string(name) == "fit-cie-study" || std::string(name) == "sky-segmentation") << name;
  }
}

// fit-cie-study's table (bench/results/cie.md's shape) from hand-made fits: the per-sky
// cell, the per-elevation median and the summary row, in percent.
TEST(BenchStudySuites, CieStudyMarkdownFromHandMadeFits) {
  const SuiteRegistry registry = BuiltinSuites();  // owns the suite (a temporary's would dangle)
  const Suite* s = registry.Find("fit-cie-study");
  ASSERT_NE(s, nullptr);
  CaseResult c = MakeCase("fit-cie-study", {{"model", "ffxv-iso"}}, T(900, 900, 900, 1), 0.0201, true);
  nlohmann::json fits = nlohmann::json::array();
  const double rel[3] = {0.0201, 0.0100, 0.0374};
  for (int t = 1; t <= 3; ++t)
    fits.push_back({{"sky_type", t}, {"sun_elevation_deg", 30.0}, {"rel_rmse", rel[t - 1]}, {"log_rmse", 0.02},
                    {"haziness_g", 0.7}, {"time_s", 0.1 * t},
                    {"breakdown", {{"circumsolar_3_15deg", 0.05}, {"horizon_0_10deg", 0.01}, {"rest", 0.015}}}});
  c.extra = {{"fits", fits}};
  const std::string md = s->markdown({c});
  EXPECT_NE(md.find("| ffxv-iso 30° |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 3 | "), std::string::npos) << md;      // type 3's row
  EXPECT_NE(md.find(" 3.74 |"), std::string::npos) << md;      // its cell, %
  EXPECT_NE(md.find("**2.01**"), std::string::npos) << md;     // the median of 2.01, 1.00, 3.74
  EXPECT_NE(md.find("type 3, 30°: 3.74"), std::string::npos) << md;  // the worst first
  EXPECT_NE(md.find("| 0.20 |"), std::string::npos) << md;     // median time per fit, s
  EXPECT_NE(md.find("**not met** (2.01%)"), std::string::npos) << md;
}

// fit-decisions (the retired bench_fit --decisions): every decision's on/off pair is two
// cases of the grid, and the table pairs them: saved = off - on, change = on - off (pp).
TEST(BenchLastSuites, FitDecisionsGridAndTableFromHandMadeCases) {
  for (const bool quick : {false, true}) {
    const FitDecisionsPlan p = FitDecisionsGridPlan(quick);
    EXPECT_EQ(Label(p.grid.Defaults()), "variant=default");
    EXPECT_EQ(p.width, quick ? 128 : 512);
    EXPECT_EQ(p.runs, quick ? 1 : 3);
    const std::vector<Settings> cases = p.grid.Expand();
    ASSERT_EQ(cases.size(), 5u);
    for (const DecisionSwitch& d : DecisionSwitches()) {
      int on = 0, off = 0;
      for (const Settings& st : cases) on += Get(st, "variant") == d.on, off += Get(st, "variant") == d.off;
      EXPECT_EQ(on, 1) << d.row;
      EXPECT_EQ(off, 1) << d.row;
      EXPECT_NE(d.on, d.off) << d.row;
    }
  }
  const SuiteRegistry registry = BuiltinSuites();
  const Suite* s = registry.Find("fit-decisions");
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(s->pareto);
  ASSERT_TRUE(static_cast<bool>(s->markdown));
  auto make = [](const std::string& variant, double ms, double rel) {
    CaseResult c = MakeCase("fit-decisions", {{"variant", variant}}, T(ms, ms, ms, 3), rel, variant == "default");
    c.extra = {{"skies", nlohmann::json::array({{{"sky", "CIE 12 sun 30"}, {"ms", ms}, {"rel_rmse", rel}, {"samples", 1000}}})},
               {"samples_median", 196410.0},
               {"below_horizon_saved_ms_median", 417.3}};
    return c;
  };
  const std::string md = s->markdown({make("default", 400.0, 0.0200), make("polish", 650.0, 0.0205)});
  // Ceres polish: on 400, off 650 -> saved 250 ms; change 2.00 - 2.05 = -0.05 pp.
  EXPECT_NE(md.find("| CIE 12 sun 30 | 400 | 650 | 250 | 2 | 2.05 | -0.05 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| Ceres polish | 250 | -0.05 | measured (switched off) |"), std::string::npos) << md;
  // The coarse-levels and overcast pairs lack a case: no row rather than a made-up one.
  EXPECT_EQ(md.find("coarse pyramid levels skipped"), std::string::npos) << md;
  EXPECT_NE(md.find("| pixels below the horizon not evaluated | 417.3 |"), std::string::npos) << md;
  EXPECT_NE(md.find("final level: 1.964e+05"), std::string::npos) << md;
}

// fit-clouds-process (the retired bench/fit_clouds.sh): relative (the default) and absolute.
TEST(BenchLastSuites, FitCloudsProcessGridAndRegistration) {
  EXPECT_EQ(FitCloudsProcessGridPlan(false).width, 512);
  EXPECT_EQ(FitCloudsProcessGridPlan(true).width, 128);
  const std::vector<Settings> cases = FitCloudsProcessGridPlan(false).grid.Expand();
  ASSERT_EQ(cases.size(), 2u);
  EXPECT_EQ(Label(cases[0]), "start=relative");
  EXPECT_EQ(Label(cases[1]), "start=absolute");
  EXPECT_EQ(Label(FitCloudsProcessGridPlan(false).grid.Defaults()), "start=relative");
  const SuiteRegistry registry = BuiltinSuites();
  const Suite* s = registry.Find("fit-clouds-process");
  ASSERT_NE(s, nullptr);
  EXPECT_FALSE(s->pareto);  // the absolute start needs the truth: not a speed setting
  ASSERT_TRUE(static_cast<bool>(s->markdown));
  CaseResult c = MakeCase("fit-clouds-process", {{"start", "relative"}}, T(2220, 2220, 2220, 1), 0.00079, true);
  c.extra = {{"cpu_s", 2.63}, {"fit_time_s", 1.56}, {"cloud_pixels", 12265}, {"cloud_log_rmse_initial", 0.00035},
             {"cloud_log_rmse_final", 0.00163}, {"clear_log_rmse", 8e-5}, {"solve", {{"iterations", 1}}}};
  const std::string md = s->markdown({c});
  EXPECT_NE(md.find("| 2.63 | 1.56 | 0.00035 | 0.00163 | 8e-05 | 1.226e+04 |"), std::string::npos) << md;
  EXPECT_NE(md.find("start=relative: clouds.solve {\"iterations\":1}"), std::string::npos) << md;
}

// The child-process runner of fit-clouds-process and fit-skies: a zero exit returns the CPU
// seconds; a failing or missing command is a clear error naming the suite and the command.
TEST(BenchLastSuites, RunProcessReportsCpuAndFailures) {
  const double cpu = RunProcessCpuS("t", {"/bin/sh", "-c", "i=0; while [ $i -lt 20000 ]; do i=$((i+1)); done"});
  EXPECT_GT(cpu, 0.0);  // a busy loop of ~50 ms: some CPU is counted
  EXPECT_LT(cpu, 30.0);
  try {
    RunProcessCpuS("fit-x", {"/bin/sh", "-c", "exit 3"});
    ADD_FAILURE() << "no error on exit 3";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fit-x: '/bin/sh -c exit 3' failed"), std::string::npos) << e.what();
  }
  EXPECT_THROW(RunProcessCpuS("fit-x", {"/nonexistent/skycal"}), Error);
}

// batch (the retired bench/batch_day.sh): five runs, warm the default. The day's sun at 70
// deg N on the June solstice (declination 23.44 deg): lowest at midnight, 23.44 - (90 - 70)
// = 3.44 deg; highest at noon, 90 - 70 + 23.44 = 43.44 deg: always above the horizon.
TEST(BenchLastSuites, BatchGridAndTheDaySun) {
  const BatchPlan full = BatchGridPlan(false), quick = BatchGridPlan(true);
  EXPECT_EQ(full.frames, 96);
  EXPECT_EQ(full.frames_per_job, 8);
  EXPECT_EQ(quick.frames, 8);
  EXPECT_EQ(quick.frames_per_job, 4);
  ASSERT_EQ(full.grid.Expand().size(), 5u);
  EXPECT_EQ(Label(full.grid.Defaults()), "run=warm");
  double el = 0, az = 0;
  BatchDaySun(12.0, &el, &az);
  EXPECT_NEAR(el, 43.44, 1e-9);
  EXPECT_NEAR(std::abs(az), 180.0, 1e-9);  // azimuth from north: due south at noon
  BatchDaySun(0.0, &el, &az);
  EXPECT_NEAR(el, 3.44, 1e-9);
  EXPECT_NEAR(az, 0.0, 1e-9);  // due north at midnight
  for (int i = 0; i < 96; ++i) {
    BatchDaySun(24.0 * i / 96, &el, &az);
    EXPECT_GE(el, 3.44 - 1e-9) << i;
    EXPECT_LE(el, 43.44 + 1e-9) << i;
  }
  const SuiteRegistry registry = BuiltinSuites();
  const Suite* s = registry.Find("batch");
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(s->pareto);
  ASSERT_TRUE(static_cast<bool>(s->markdown));
  // A skipped Slurm case shows its reason, not a row of made-up numbers.
  CaseResult skipped = MakeCase("batch", {{"run", "slurm"}}, T(0, 0, 0, 0), std::nan(""));
  skipped.outcome = Outcome::kClearError;
  skipped.message = "skipped: not root";
  const std::string md = s->markdown({skipped});
  EXPECT_NE(md.find("slurm: skipped: not root"), std::string::npos) << md;
  EXPECT_EQ(md.find("| slurm |"), std::string::npos) << md;
}

// The suites that replaced bench_cloud_stats: the configurations its results files report
// (each file exists), the quick plan, registration, and the seed-pair table from a
// hand-made case (no render).
TEST(BenchCloudStatsSuites, PlanRegistrationAndTable) {
  const CloudStatsPlan full = FitCloudStatsPlan(false);
  ASSERT_EQ(full.grid.Expand().size(), 10u);
  EXPECT_EQ(Label(full.grid.Defaults()), "config=default");
  EXPECT_EQ(full.pairs, 5);
  EXPECT_EQ(full.width_override, 0);
  EXPECT_EQ(full.iteration_cap, 0);
  for (const CloudStatsConfig& c : full.configs) {
    if (c.name == "default") continue;
    EXPECT_TRUE(std::filesystem::exists(std::string(SKYCAL_SOURCE_DIR) + "/bench/results/" + c.results_file + ".md")) << c.name;
    EXPECT_FALSE(c.fitted.empty()) << c.name;  // explicit: the options' default changed since the program ran
  }
  const CloudStatsConfig& gls = FindCloudStatsConfig(full, "gls-2params-3refs");
  EXPECT_EQ(gls.references, 3);
  EXPECT_EQ(gls.model_maps, 4);
  EXPECT_EQ(gls.noise_draws, 24);
  EXPECT_EQ(gls.fitted, (std::vector<std::string>{"extinction", "ambient_strength"}));
  EXPECT_EQ(FindCloudStatsConfig(full, "noises-2params").model_noises, 4);
  EXPECT_THROW(FindCloudStatsConfig(full, "nope"), Error);

  const CloudStatsPlan quick = FitCloudStatsPlan(true);
  ASSERT_EQ(quick.grid.Expand().size(), 2u);
  EXPECT_EQ(Label(quick.grid.Defaults()), "config=default");
  EXPECT_EQ(quick.pairs, 1);
  EXPECT_EQ(quick.width_override, 64);
  EXPECT_EQ(quick.iteration_cap, 2);
  EXPECT_EQ(CloudStatsNoiseGridPlan(false).draws, 48);
  EXPECT_EQ(CloudStatsNoiseGridPlan(false).model_maps, 4);
  EXPECT_EQ(CloudStatsNoiseGridPlan(true).draws, 8);

  // fit-cloud-stats-gls: diagonal and full whitening on the same draws (24 maps x 6 noise textures).
  const CloudStatsPlan gls_plan = FitCloudStatsGlsPlan(false);
  ASSERT_EQ(gls_plan.grid.Expand().size(), 10u);
  EXPECT_EQ(gls_plan.pairs, 5);
  for (const CloudStatsConfig& c : gls_plan.configs) {
    const bool test = c.name.rfind("test-", 0) == 0;  // the recovery test's settings
    EXPECT_EQ(c.noise_draws, test ? 8 : 24) << c.name;
    EXPECT_EQ(c.draw_noises, test ? 2 : 6) << c.name;
    EXPECT_EQ(c.covariance, c.name.find("diag") != std::string::npos ? "diagonal" : "full") << c.name;
  }
  EXPECT_EQ(FindCloudStatsConfig(gls_plan, "full-2params-low").extinction_start, 0.7);
  EXPECT_EQ(FitCloudStatsGlsPlan(true).grid.Expand().size(), 3u);
  EXPECT_EQ(FitCloudStatsGlsPlan(true).pairs, 5);

  const SuiteRegistry r = BuiltinSuites();
  for (const char* name : {"fit-cloud-stats", "fit-cloud-stats-gls", "cloud-stats-noise"}) {
    const Suite* s = r.Find(name);
    ASSERT_NE(s, nullptr) << name;
    EXPECT_TRUE(static_cast<bool>(s->markdown)) << name;
    EXPECT_FALSE(s->error_metric.empty()) << name;
    EXPECT_EQ(s->pareto, std::string(name) != "cloud-stats-noise") << name;
  }

  CaseResult c = MakeCase("fit-cloud-stats", {{"config", "default"}}, T(5000, 5000, 5000, 1), 0.095, true);
  auto row = [](bool control, int k, double ext, double amb) {
    nlohmann::json r = {{"control_known_shapes", control},
                        {"reference_seeds", {1 + k, 11 + k}},
                        {"model_seeds", control ? nlohmann::json{1 + k, 11 + k} : nlohmann::json{101 + k, 211 + k}},
                        {"initial_cost", 0.316},
                        {"final_cost", 0.296},
                        {"iterations", 3},
                        {"renders", 42},
                        {"time_s", 1.84}};
    for (const char* n : {"extinction", "phase_g1", "powder_strength", "ambient_strength"})
      r["parameters"][n] = {{"rel_error", 0.0}};
    r["parameters"]["extinction"]["rel_error"] = ext;
    r["parameters"]["ambient_strength"]["rel_error"] = amb;
    return r;
  };
  nlohmann::json spread;
  for (const char* n : {"extinction", "phase_g1", "powder_strength", "ambient_strength"})
    spread[n] = {{"median_abs_rel_error", 0.0}, {"max_abs_rel_error", 0.0}};
  spread["extinction"] = {{"median_abs_rel_error", 0.095}, {"max_abs_rel_error", 0.095}};
  c.extra = {{"runs", {row(true, 0, 0.001, -0.0004), row(false, 1, 0.095, 0.047)}},
             {"spread", spread}, {"pairs", 1}, {"render_width", 64}, {"references_per_fit", 1},
             {"model_weather_maps", 1}, {"model_renders", 2}, {"max_iterations", 2},
             {"fitted", "extinction,ambient_strength"}, {"noise_draws", 0}, {"model_noise_textures", 1}};
  const std::string md = r.Find("fit-cloud-stats")->markdown({c});
  EXPECT_NE(md.find("## default (the default)"), std::string::npos) << md;
  EXPECT_NE(md.find("| control (same seeds) | +0.1% | +0.0% | +0.0% | -0.0% |"), std::string::npos) << md;
  // Rows written before the albedo column have "-" there.
  EXPECT_NE(md.find("| 2/12 vs 102/212 | +9.5% | +0.0% | +0.0% | +4.7% | - | 0.316 -> 0.296 | 3 | 42 | 1.8 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| extinction | 9.5% | 9.5% |"), std::string::npos) << md;
  EXPECT_NE(md.find("weighted by bin share"), std::string::npos) << md;
}

// The capture suite compares a coarse frame with the scene's area mean at the frame's nodes.
TEST(BenchImageCompare, AreaMeanAtNodesKeepsAConstantAndAveragesDetailAway) {
  ImageRGB flat(256, 128);
  for (float& v : flat.pixels) v = 2.5f;
  const ImageRGB flat_mean = bench::AreaMeanAtNodes(flat, 64, 32);
  for (float v : flat_mean.pixels) ASSERT_NEAR(v, 2.5f, 1e-5f);
  // A one-pixel checkerboard of 1 and 3: every node of a 4x coarser grid averages it to ~2,
  // and the relative error of that mean against the point-sampled truth is ~50% (the
  // detail a coarse grid cannot hold), against ~0 for the area mean.
  ImageRGB checker(256, 128);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c) checker.at(x, y, c) = ((x + y) % 2) ? 3.0f : 1.0f;
  const ImageRGB mean = bench::AreaMeanAtNodes(checker, 64, 32);
  for (int y = 2; y < 30; ++y)  // the poles' nodes gather few pixels
    for (int x = 0; x < 64; ++x) ASSERT_NEAR(mean.at(x, y, 0), 2.0f, 0.35f) << x << "," << y;
  ImageRGB coarse(64, 32);
  for (float& v : coarse.pixels) v = 2.0f;
  EXPECT_GT(bench::RelRmse(checker, coarse, 10.0), 0.4);
  EXPECT_LT(bench::RelRmse(mean, coarse, 10.0), 0.12);
}

TEST(BenchPareto, ExactMembershipOnAHandMadeSet) {
  // (time, error): 0 and 1 trade off; 2 is dominated by 1; 3 ties 0 exactly (both kept);
  // 4 is fastest but worst; 5 is not finite; 6 equals 1 in time and is worse in error.
  const std::vector<TimeError> pts = {{1.0, 0.5}, {2.0, 0.1}, {3.0, 0.2}, {1.0, 0.5}, {0.5, 9.0}, {NAN, 0.0}, {2.0, 0.3}};
  EXPECT_EQ(ParetoFront(pts), (std::vector<int>{0, 1, 3, 4}));
  EXPECT_TRUE(ParetoFront({}).empty());
  // With tolerances: 5% faster at the same error is noise (both kept), 20% faster is not;
  // 0.5% more accurate at 3x the time is not better either.
  const std::vector<TimeError> noisy = {{100, 0.01}, {95, 0.01}, {80, 0.01}, {300, 0.00995}};
  EXPECT_EQ(ParetoFront(noisy), (std::vector<int>{2, 3}));
  EXPECT_EQ(ParetoFront({{100, 0.01}, {95, 0.01}}, {0.10, 0.01}), (std::vector<int>{0, 1}));
  EXPECT_EQ(ParetoFront(noisy, {0.10, 0.01}), (std::vector<int>{2}));
}

TEST(BenchCompare, FlagsAPlanted2xRegressionAndNotA5PercentWobble) {
  Results old_run, new_run;
  old_run.machine.commit = "old";
  new_run.machine.commit = "new";
  // Noise: spread (max - min) / median = 10% in both runs.
  old_run.cases = {MakeCase("render", {{"size", "512"}}, T(100, 95, 105), 0.01),
                   MakeCase("render", {{"size", "1024"}}, T(400, 380, 420), 0.005),
                   MakeCase("fit", {{"loss", "cauchy"}}, T(250, 240, 265), 0.02)};
  new_run.cases = {MakeCase("render", {{"size", "512"}}, T(200, 190, 210), 0.01),    // planted 2x
                   MakeCase("render", {{"size", "1024"}}, T(420, 400, 440), 0.005),  // 5% wobble
                   MakeCase("fit", {{"loss", "cauchy"}}, T(250, 240, 265), 0.04)};   // error doubled
  const Comparison c = Compare(old_run, new_run, CompareOptions{});
  ASSERT_EQ(c.cases.size(), 3u);
  EXPECT_EQ(c.cases[0].verdict, Verdict::kSlower);
  EXPECT_DOUBLE_EQ(c.cases[0].ratio, 2.0);
  EXPECT_EQ(c.cases[1].verdict, Verdict::kSame);
  EXPECT_NEAR(c.cases[1].ratio, 1.05, 1e-12);
  EXPECT_EQ(c.cases[2].verdict, Verdict::kSame);
  EXPECT_TRUE(c.cases[2].error_worse);
  EXPECT_EQ(c.slower, 1);
  EXPECT_EQ(c.error_worse, 1);
  EXPECT_TRUE(c.Regressed());
  // A noisy case (spread 150%) hides a 2x change: not flagged.
  old_run.cases = {MakeCase("render", {{"size", "512"}}, T(100, 50, 200), 0.01)};
  new_run.cases = {MakeCase("render", {{"size", "512"}}, T(200, 190, 210), 0.01)};
  EXPECT_EQ(Compare(old_run, new_run, CompareOptions{}).cases[0].verdict, Verdict::kSame);
  // One-run cases (no spread): the 10% floor still keeps a 5% wobble unflagged.
  old_run.cases = {MakeCase("x", {{"a", "1"}}, T(100, 100, 100, 1), 0.0)};
  new_run.cases = {MakeCase("x", {{"a", "1"}}, T(105, 105, 105, 1), 0.0), MakeCase("x", {{"a", "2"}}, T(1, 1, 1, 1), 0.0)};
  const Comparison d = Compare(old_run, new_run, CompareOptions{});
  EXPECT_EQ(d.cases[0].verdict, Verdict::kSame);
  EXPECT_EQ(d.cases[1].verdict, Verdict::kOnlyNew);
  EXPECT_FALSE(d.Regressed());
  // An untimed case (a stress input, one run) is compared by outcome only, not by time.
  new_run.cases = {MakeCase("x", {{"a", "1"}}, T(300, 300, 300, 1), 0.0)};
  new_run.cases[0].timed = false;
  new_run.cases[0].outcome = Outcome::kNonFinite;
  const Comparison u = Compare(old_run, new_run, CompareOptions{});
  EXPECT_EQ(u.cases[0].verdict, Verdict::kSame);
  EXPECT_EQ(u.outcome_worse, 1);
}

TEST(BenchCompare, AnOldMedianOfZeroIsNotSame) {
  // A case too fast to time in the old run (median 0 ms) and measurable now: a regression
  // of unbounded ratio, not "same" (the ratio used to be NaN, which no test flags).
  Results old_run, new_run;
  old_run.cases = {MakeCase("x", {{"a", "1"}}, T(0, 0, 0, 1), 0.0), MakeCase("x", {{"a", "2"}}, T(0, 0, 0, 1), 0.0)};
  new_run.cases = {MakeCase("x", {{"a", "1"}}, T(5, 5, 5, 1), 0.0), MakeCase("x", {{"a", "2"}}, T(0, 0, 0, 1), 0.0)};
  const Comparison c = Compare(old_run, new_run, CompareOptions{});
  ASSERT_EQ(c.cases.size(), 2u);
  EXPECT_EQ(c.cases[0].verdict, Verdict::kSlower);
  EXPECT_TRUE(std::isinf(c.cases[0].ratio));
  EXPECT_EQ(c.cases[1].verdict, Verdict::kSame);  // 0 then 0: the same
  EXPECT_EQ(c.cases[1].ratio, 1.0);
  EXPECT_TRUE(c.Regressed());
}

TEST(BenchStressTable, CountsOutcomesPerArea) {
  std::vector<CaseResult> cases;
  auto add = [&](const std::string& area, Outcome o, std::optional<bool> conv) {
    CaseResult c = MakeCase("stress", {{"area", area}, {"input", std::to_string(cases.size())}}, T(1, 1, 1, 1), NAN);
    c.outcome = o;
    c.converged = conv;
    cases.push_back(c);
  };
  add("render", Outcome::kOk, std::nullopt);
  add("render", Outcome::kNonFinite, std::nullopt);
  add("fit", Outcome::kOk, true);
  add("fit", Outcome::kOk, false);
  add("fit", Outcome::kClearError, std::nullopt);
  const auto table = StressTable(cases);
  ASSERT_EQ(table.size(), 2u);
  EXPECT_EQ(table[0].area, "render");
  EXPECT_EQ(table[0].cases, 2);
  EXPECT_DOUBLE_EQ(table[0].FinitePercent(), 50.0);
  EXPECT_FALSE(table[0].Passed());
  EXPECT_EQ(table[1].clear_error, 1);
  EXPECT_EQ(table[1].with_convergence, 2);
  EXPECT_EQ(table[1].converged, 1);
  EXPECT_TRUE(table[1].Passed());
  EXPECT_DOUBLE_EQ(StressTableToJson(table)[1]["converged_percent"].get<double>(), 50.0);
}

TEST(BenchVerb, WritesResultsJsonCsvAndPlots) {
  skycal::testing::ScratchDir dir("bench-verb");
  cli::BenchOptions o;
  o.suites = "fake";
  o.out = dir / "results";
  const nlohmann::json summary = cli::RunBenchImpl(o, FakeRegistry());
  const nlohmann::json j = ReadJsonFile(dir / "results/results.json");
  EXPECT_EQ(j["schema"], kResultsSchema);
  EXPECT_EQ(j["version"], kResultsVersion);
  for (const char* k : {"cpu_model", "cores", "vulkan_device", "commit", "commit_dirty", "date_utc", "skycal_version"})
    EXPECT_TRUE(j["machine"].contains(k)) << k;
  EXPECT_GE(j["machine"]["cores"].get<int>(), 1);
  EXPECT_EQ(j["machine"]["date_utc"].get<std::string>().size(), 20u);  // 2026-01-01T00:00:00Z
  ASSERT_EQ(j["cases"].size(), 4u);
  const auto& c0 = j["cases"][0];
  for (const char* k : {"suite", "case", "settings", "default", "time_ms", "timed", "error", "outcome", "message", "converged", "extra"})
    EXPECT_TRUE(c0.contains(k)) << k;
  EXPECT_EQ(c0["case"], "size=small method=a");
  EXPECT_DOUBLE_EQ(c0["time_ms"]["median_ms"].get<double>(), 1.0);
  // Front: (1, 0.1) and (10, 0.01); (2, 0.2) and (20, 0.02) dominated (beyond the 10% / 1%
  // tolerances too). Default large/a on it.
  ASSERT_EQ(j["suites"].size(), 1u);
  EXPECT_EQ(j["suites"][0]["pareto_front"], nlohmann::json({"size=small method=a", "size=large method=a"}));
  EXPECT_EQ(j["suites"][0]["default_case"], "size=large method=a");
  EXPECT_TRUE(j["suites"][0]["default_on_front"].get<bool>());
  // CSV: the header and one row per case, the front column matching.
  std::istringstream csv(ReadText(dir / "results/results.csv"));
  std::string line;
  std::getline(csv, line);
  std::string header;
  for (const std::string& c : CsvColumns()) header += (header.empty() ? "" : ",") + c;
  EXPECT_EQ(line, header);
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].rfind("fake,size=small method=a,0,1,0.9,1.1,5,0.1,rel error,ok,,1,", 0), 0u) << rows[0];
  EXPECT_EQ(rows[1].rfind("fake,size=small method=b,0,2,", 0), 0u) << rows[1];
  EXPECT_NE(rows[1].find(",ok,,0,"), std::string::npos) << rows[1];
  // The suite's own table (Suite::markdown) as DIR/<suite>.md.
  EXPECT_EQ(ReadText(dir / "results/fake.md"), "# fake\n4 cases\n");
  // Plots: a PNG (its signature) and an SVG.
  EXPECT_EQ(ReadText(dir / "results/fake_pareto.png").substr(1, 3), "PNG");
  EXPECT_NE(ReadText(dir / "results/fake_pareto.svg").find("<svg"), std::string::npos);
  // The report (skycal report of the results directory): the suite's plot embedded.
  const std::string html = ReadText(dir / "results/report.html");
  EXPECT_NE(html.find("<h2>Benchmark: results</h2>"), std::string::npos);
  EXPECT_NE(html.find("alt=\"fake Pareto plot\""), std::string::npos);
  // The JSON reads back as it was written.
  const Results back = ResultsFromJson(j, "results.json");
  ASSERT_EQ(back.cases.size(), 4u);
  EXPECT_EQ(back.cases[3].settings, (Settings{{"size", "large"}, {"method", "b"}}));
  EXPECT_DOUBLE_EQ(back.cases[3].error, 0.02);
  // A second run replaces its own earlier output.
  EXPECT_NO_THROW(cli::RunBenchImpl(o, FakeRegistry()));
}

TEST(BenchVerb, ReplotRedrawsAnEarlierRunWithoutTouchingIt) {
  skycal::testing::ScratchDir dir("bench-replot");
  cli::BenchOptions o;
  o.suites = "fake";
  o.out = dir / "results";
  cli::RunBenchImpl(o, FakeRegistry());
  const std::string before = ReadText(dir / "results/results.json");
  cli::BenchOptions r;
  r.replot = dir / "results/results.json";
  r.out = dir / "redrawn";
  const nlohmann::json summary = cli::RunBenchImpl(r, FakeRegistry());
  const nlohmann::json j = ReadJsonFile(dir / "redrawn/results.json");
  ASSERT_EQ(j["suites"].size(), 1u);
  EXPECT_EQ(j["suites"][0]["pareto_front"], nlohmann::json({"size=small method=a", "size=large method=a"}));
  EXPECT_EQ(j["cases"].size(), 4u);
  EXPECT_EQ(ReadText(dir / "redrawn/fake_pareto.png").substr(1, 3), "PNG");
  EXPECT_EQ(ReadText(dir / "results/results.json"), before);
  // Redrawing into the directory the input lives in would replace it: refused.
  r.out = dir / "results";
  EXPECT_THROW(cli::RunBenchImpl(r, FakeRegistry()), Error);
  EXPECT_EQ(ReadText(dir / "results/results.json"), before);
  // --replot runs nothing: no --suite beside it.
  r.suites = "fake";
  std::string why;
  EXPECT_FALSE(r.IsValid(&why));
}

TEST(BenchVerb, FailsAfterWritingWhenACaseIsNonFinite) {
  skycal::testing::ScratchDir dir("bench-nonfinite");
  cli::BenchOptions o;
  o.suites = "fake";
  o.out = dir / "results";
  EXPECT_THROW(cli::RunBenchImpl(o, FakeRegistry(Outcome::kNonFinite)), Error);
  const nlohmann::json j = ReadJsonFile(dir / "results/results.json");
  EXPECT_EQ(j["cases"][3]["outcome"], "non_finite");
}

TEST(BenchVerb, BadInput) {
  skycal::testing::ScratchDir dir("bench-bad");
  cli::BenchOptions o;
  o.suites = "render,nosuch";
  o.out = dir / "results";
  try {
    cli::RunBenchImpl(o, BuiltinSuites());
    FAIL() << "unknown suite accepted";
  } catch (const Error& e) {
    // The message names the unknown suite and lists every registered one.
    const std::string what = e.what();
    EXPECT_NE(what.find("unknown suite 'nosuch' (valid: render, fit, fit-day, "), std::string::npos) << what;
    for (const std::string& name : BuiltinSuites().Names())
      EXPECT_NE(what.find(" " + name + (name == "clouds" ? ")" : ",")), std::string::npos) << name << ": " << what;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "results"));
  // A user's directory is never replaced.
  std::filesystem::create_directories(dir / "mine");
  skycal::testing::WriteText(dir / "mine/notes.txt", "mine");
  o.suites = "fake";
  o.out = dir / "mine";
  try {
    cli::RunBenchImpl(o, FakeRegistry());
    FAIL() << "a user's directory was replaced";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("refusing to replace it"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadText(dir / "mine/notes.txt"), "mine");
  // --repeat: integers in [1, 1000].
  for (const char* bad : {"0", "1.5", "-3", "1001", "x"}) {
    std::vector<std::string> args = {"--suite", "render", "--repeat", bad, "--out", "o"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    EXPECT_THROW(cli::ParseBenchArgs(static_cast<int>(argv.size()), argv.data()), Error) << bad;
  }
  cli::BenchOptions r;
  r.suites = "fake";
  r.out = dir / "r";
  r.repeat = -1;
  EXPECT_THROW(cli::RunBenchImpl(r, FakeRegistry()), Error);
  // --compare takes exactly two files and runs nothing else.
  cli::BenchOptions c;
  c.compare = {"a.json"};
  std::string why;
  EXPECT_FALSE(c.IsValid(&why));
  c.compare = {"a.json", "b.json"};
  c.out = "x";
  EXPECT_FALSE(c.IsValid(&why));
}

TEST(BenchVerb, CompareReadsTwoResultsFiles) {
  skycal::testing::ScratchDir dir("bench-compare");
  Results a, b;
  a.machine.commit = "a";
  b.machine.commit = "b";
  a.cases = {MakeCase("render", {{"size", "512"}}, T(100, 95, 105), 0.01)};
  b.cases = {MakeCase("render", {{"size", "512"}}, T(200, 190, 210), 0.01)};
  WriteJsonFileAtomically(dir / "a.json", ToJson(a));
  WriteJsonFileAtomically(dir / "b.json", ToJson(b));
  cli::BenchOptions o;
  o.compare = {dir / "a.json", dir / "b.json"};
  const nlohmann::json j = cli::RunBenchImpl(o, FakeRegistry());
  EXPECT_EQ(j["slower"], 1);
  EXPECT_TRUE(j["regressed"].get<bool>());
  EXPECT_EQ(j["cases"][0]["verdict"], "SLOWER");
  EXPECT_TRUE(j.value("verb_failed", false));
  // The verb's exit code: 1 on a regression (the summary still printed), 0 on a run against itself.
  EXPECT_EQ(cli::RunVerb("bench", false, [&] { return cli::RunBenchImpl(o, FakeRegistry()); }), 1);
  cli::BenchOptions same = o;
  same.compare = {dir / "a.json", dir / "a.json"};
  EXPECT_EQ(cli::RunVerb("bench", false, [&] { return cli::RunBenchImpl(same, FakeRegistry()); }), 0);
  skycal::testing::WriteText(dir / "c.json", "{\"schema\": \"other\"}");
  o.compare = {dir / "a.json", dir / "c.json"};
  EXPECT_THROW(cli::RunBenchImpl(o, FakeRegistry()), Error);
}

namespace skycal::bench {
namespace {

// The clouds-error suite's split of the squared error: each split (elevation bands, the
// reference's opacity classes) sums to the whole error squared (RelRmse's, in %^2); the
// cloud-pixel error sees only pixels with T < 0.99. Control: an error planted in a clear
// pixel only shows in e2_clear and leaves the cloud-pixel error 0.
TEST(BenchCloudsError, SquaredErrorSplitsSumToTheWhole) {
  ConvergedCloudReference ref;
  ref.truth = ImageRGB(32, 16);
  ref.clouds.transmittance.assign(32 * 16, 1.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < 3; ++c) ref.truth.at(x, y, c) = 1.0f + 0.1f * static_cast<float>((x * 7 + y * 3 + c) % 11);
      ref.clouds.transmittance[static_cast<size_t>(y) * 32 + x] = static_cast<float>((x + 2 * y) % 5) * 0.25f;  // 0 .. 1
    }
  ImageRGB image = ref.truth;
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] *= 1.0f + 0.02f * static_cast<float>(i % 7) - 0.05f;
  CaseResult c;
  CloudErrorParts(ref, image, c);
  const double whole = 1e4 * std::pow(RelRmse(ref.truth, image, 0.0), 2);
  double bands = 0.0, classes = 0.0;
  for (const char* k : {"e2_elev_0_5", "e2_elev_5_15", "e2_elev_15_45", "e2_elev_45_90"}) bands += c.extra.value(k, 0.0);
  for (const char* k : {"e2_clear", "e2_thin", "e2_medium", "e2_thick"}) classes += c.extra.value(k, 0.0);
  EXPECT_NEAR(bands, whole, 1e-9 * whole);
  EXPECT_NEAR(classes, whole, 1e-9 * whole);
  EXPECT_GT(c.extra["rel_rmse_cloud_pixels"].get<double>(), 0.0);

  ImageRGB one = ref.truth;  // the control: one clear pixel (T = 1) 10% too bright
  ASSERT_EQ(ref.clouds.transmittance[2 * 32 + 0], 1.0f);
  for (int ch = 0; ch < 3; ++ch) one.at(0, 2, ch) *= 1.1f;
  CaseResult d;
  CloudErrorParts(ref, one, d);
  EXPECT_GT(d.extra.value("e2_clear", 0.0), 0.0);
  EXPECT_EQ(d.extra.value("e2_thin", 0.0) + d.extra.value("e2_medium", 0.0) + d.extra.value("e2_thick", 0.0), 0.0);
  EXPECT_EQ(d.extra["rel_rmse_cloud_pixels"].get<double>(), 0.0);
}

}  // namespace
}  // namespace skycal::bench
