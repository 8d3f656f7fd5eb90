// The verbs' Parse<Verb>Args (cli/command_line.h): options into the verb's struct without
// running it and without touching a file (what a fuzz harness of the command line needs),
// help as HelpRequested, and bad command lines as skycal::Error naming the option.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "capture_verb.h"
#include "command_line.h"
#include "export_verb.h"
#include "fit_verb.h"
#include "render_verb.h"
#include "skycal/core/error.h"
#include "sun_verb.h"

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

}  // namespace
}  // namespace skycal::cli
