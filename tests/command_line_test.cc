// The verbs' Parse<Verb>Args (cli/command_line.h): options into the verb's struct without
// running it and without touching a file (what a fuzz harness of the command line needs),
// help as HelpRequested, and bad command lines as skycal::Error naming the option.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "batch_verb.h"
#include "capture_verb.h"
#include "command_line.h"
#include "export_verb.h"
#include "fit_verb.h"
#include "flow_verb.h"
#include "render_verb.h"
#include "report_verb.h"
#include "skycal/core/error.h"
#include "sun_verb.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

// argv from words (the arguments after the verb); the strings outlive the call.
class Argv {
 public:
  explicit Argv(std::vector<std::string> words) : words_(std::move(words)) {
    for (auto& w : words_) pointers_.push_back(w.data());
  }
  int argc() { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

template <typename Parse>
std::string ErrorOf(Parse parse, std::vector<std::string> words) {
  Argv a(std::move(words));
  try {
    parse(a.argc(), a.argv());
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(CommandLine, RenderParsesWithoutTouchingFiles) {
  // Paths that do not exist are only collected: the verb checks them when it runs.
  Argv a({"--preset", "/nonexistent/p.json", "--sun-dir=0,1,0", "--size", "64x32", "--backend", "cpu", "--ground=zero",
          "--no-sun-disc", "--half", "--out", "/nonexistent/dir/o.exr", "--exposure", "-2.5"});
  const RenderOptions o = ParseRenderArgs(a.argc(), a.argv());
  EXPECT_EQ(o.preset_path, "/nonexistent/p.json");
  ASSERT_TRUE(o.sun_dir.has_value());
  EXPECT_EQ((*o.sun_dir)[1], 1.0);
  EXPECT_FALSE(o.sun_elevation_deg.has_value());
  EXPECT_EQ(o.width, 64);
  EXPECT_EQ(o.height, 32);
  EXPECT_EQ(o.backend, render::Backend::kCpu);
  EXPECT_EQ(o.ground, render::GroundMode::kZero);
  EXPECT_FALSE(o.sun_disc);
  EXPECT_TRUE(o.half);
  EXPECT_EQ(o.out_exr, "/nonexistent/dir/o.exr");
  EXPECT_EQ(o.png_exposure_ev, -2.5);
}

TEST(CommandLine, DefaultsWhenNothingIsGiven) {
  Argv a({});
  const SunOptions o = ParseSunArgs(a.argc(), a.argv());
  const SunOptions d;
  EXPECT_EQ(o.pressure_mbar, d.pressure_mbar);
  EXPECT_EQ(o.delta_t_s, d.delta_t_s);
  EXPECT_FALSE(o.latitude_deg.has_value());
  EXPECT_TRUE(o.time.empty());
}

TEST(CommandLine, RepeatableOptionsCollectInOrder) {
  Argv f({"--reference", "a.exr", "--reference=b.exr", "--probe", "a=pa.json", "--probe", "b=pb.json", "--require-probe",
          "--time", "9.5", "--pyramid", "64,128", "--out", "d"});
  const FitCommandLine c = ParseFitArgs(f.argc(), f.argv());
  EXPECT_EQ(c.options.references, (std::vector<std::string>{"a.exr", "b.exr"}));
  EXPECT_EQ(c.probes.probes, (std::vector<std::string>{"a=pa.json", "b=pb.json"}));
  EXPECT_TRUE(c.probes.require_probe);
  EXPECT_EQ(c.options.fit.time_of_day_h, 9.5);
  EXPECT_EQ(c.options.fit.pyramid_widths, (std::vector<int>{64, 128}));
  Argv e({"--preset", "p1.json", "--preset", "p2.json", "--out", "g"});
  EXPECT_EQ(ParseExportArgs(e.argc(), e.argv()).presets, (std::vector<std::string>{"p1.json", "p2.json"}));
  // --brackets takes every argument up to the next option, and may be repeated.
  Argv b({"--brackets", "a.jpg", "b.jpg", "--out", "f.exr", "--brackets", "c.jpg"});
  EXPECT_EQ(ParseCaptureArgs(b.argc(), b.argv()).brackets, (std::vector<std::string>{"a.jpg", "b.jpg", "c.jpg"}));
}

TEST(CommandLine, HelpIsRequestedNotPrinted) {
  Argv a({"--lat", "nan", "--help"});
  try {
    ParseSunArgs(a.argc(), a.argv());
    FAIL() << "no HelpRequested";
  } catch (const HelpRequested& h) {
    EXPECT_NE(h.help().find("--north-longitude DEG"), std::string::npos) << h.help();
  }
}

TEST(CommandLine, ErrorsNameTheOption) {
  EXPECT_EQ(ErrorOf(ParseSunArgs, {"--lat", "1", "--lat", "2"}), "--lat: given 2 times; it is not repeatable (give it once)");
  EXPECT_EQ(ErrorOf(ParseSunArgs, {"--json", "--json"}), "--json: given 2 times; it is not repeatable (give it once)");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--out"}), "--out: expected a value");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--sun-elevation", "inf"}), "--sun-elevation: expected a finite number, got 'inf'");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--sun-dir", "1,2"}), "--sun-dir: expected X,Y,Z, got '1,2'");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--size", "64x0"}), "--size: expected positive integers WIDTHxHEIGHT, got '64x0'");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--bogus"}), "unknown option '--bogus' (see --help)");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"-x"}), "unknown option '-x' (see --help)");
  EXPECT_EQ(ErrorOf(ParseRenderArgs, {"--", "--out"}), "unexpected argument '--out' (options start with --; see --help)");
  EXPECT_EQ(ErrorOf(ParseFitArgs, {"--max-iterations", "2.5"}), "--max-iterations: expected an integer, got 2.5");
  EXPECT_EQ(ErrorOf(ParseFitArgs, {"--sun-elevation", "10"}), "--sun-elevation and --sun-azimuth go together");
  EXPECT_EQ(ErrorOf(ParseCaptureArgs, {"--exposure-times", "0.1,nan"}),
            "--exposure-times: expected a finite number, got 'nan'");
}


// The libraries name their options' fields (Ceres style); the verbs write them as the flags.
TEST(CommandLine, FieldsAsFlagsRewritesWholeFieldNamesOnly) {
  const FieldFlag table[] = {{"X::width", "--width"}, {"X::out", "--out"}};
  EXPECT_EQ(FieldsAsFlags("X::width = 7 (expected an even width)", table), "--width 7 (expected an even width)");
  EXPECT_EQ(FieldsAsFlags("X::out: needs X::width", table), "--out: needs --width");
  // A longer name that starts with a field's is another field: left alone.
  EXPECT_EQ(FieldsAsFlags("X::width_px = 7, X::outer = 1", table), "X::width_px = 7, X::outer = 1");
  EXPECT_EQ(FieldsAsFlags("X::width = 1, X::width = 2", table), "--width 1, --width 2");
  EXPECT_EQ(FieldsAsFlags("Y::width = 7", table), "Y::width = 7");
}

// What the user sees: the library's field named as the flag that set it, with its value.
template <typename Parse, typename Run>
std::string RunErrorOf(Parse parse, Run run, std::vector<std::string> words) {
  Argv a(std::move(words));
  try {
    run(parse(a.argc(), a.argv()));
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(CommandLine, LibraryFieldsReachTheUserAsTheirFlags) {
  BatchOptions (*parse_batch)(int, char**) = ParseBatchArgs;
  auto fit = [](const FitCommandLine& c) {
    std::string why;
    if (!c.options.IsValid(&why)) throw Error(why);
  };
  EXPECT_EQ(RunErrorOf(ParseFitArgs, fit, {"--reference", "a.exr", "--out", "d", "--sun-cone", "90"}),
            "--sun-cone 90 (expected degrees in [0, 45])");
  EXPECT_EQ(RunErrorOf(ParseFitArgs, fit, {"--reference", "a.exr", "--out", "d", "--pyramid", "64,32"}),
            "--pyramid 64,32 (expected increasing even widths in [16, 16384] pixels; 32 is not)");
  EXPECT_EQ(RunErrorOf(ParseCaptureArgs, RunCaptureImpl, {"--brackets", "a.png", "b.png", "--north-longitude", "400", "--out", "f.exr"}),
            "--north-longitude 400 (expected degrees in [-360, 360])");
  EXPECT_EQ(RunErrorOf(ParseCaptureArgs, RunCaptureImpl, {"--brackets", "a.png", "b.png", "--lat", "10", "--out", "f.exr"}),
            "--time, --lat and --lon go together (the sun by NREL SPA needs all three)");
  EXPECT_EQ(RunErrorOf(ParseExportArgs, RunExportImpl, {"--preset", "p.json", "--out", "g", "--headroom", "2"}),
            "--headroom 2 (expected a fraction in (0, 1])");
  EXPECT_EQ(RunErrorOf(parse_batch, RunBatchImpl, {"--references", "d/*.exr", "--out", "b", "--poll", "0.01"}),
            "--poll 0.01 (expected seconds in [0.05, 600])");
  EXPECT_EQ(RunErrorOf(parse_batch, RunBatchImpl, {"--references", "d/*.exr", "--out", "b", "--frame-job", "fit", "--loss-scale", "0"}),
            "--loss-scale 0 (expected natural-log units in (0, 10])");
  EXPECT_EQ(RunErrorOf(ParseFlowArgs, RunFlowImpl, {"a.exr", "b.exr", "--out", "v.png"}),
            "--out v.png (expected a path ending in .exr; V.png and V.json are written beside it)");
  auto report = [](const ReportVerbOptions& o) {
    std::string why;
    if (!o.IsValid(&why)) throw Error(why);
  };
  EXPECT_EQ(RunErrorOf(ParseReportArgs, report, {"dir", "--out", "r.txt"}),
            "--out r.txt: the HTML report is written there, expected a name ending in .html or .htm");
}

// The library's own texts: the field and its value, never a flag.
TEST(ExportOptions, IsValidNamesTheFieldAndItsValue) {
  ExportOptions o;
  o.presets = {"p.json"};
  o.out_dir = "g";
  o.fog_sigma_deg = 45.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ExportOptions::fog_sigma_deg = 45 (expected degrees in (0, 30])");
}

TEST(BatchOptions, IsValidNamesTheFieldAndItsValue) {
  BatchOptions o;
  o.references_glob = "d/*.exr";
  o.out_dir = "b";
  o.frames_per_job = 0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "BatchOptions::frames_per_job = 0 (expected a positive integer)");
  o.frames_per_job = 8;
  o.fit.clip_fraction = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FitOptions::clip_fraction = 1.5 (expected a fraction in (0, 1])");
}

}  // namespace
}  // namespace skycal::cli
