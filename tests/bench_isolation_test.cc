// `skycal bench`'s crash isolation (skycal/bench/isolated_run.h): a case that kills its
// worker process becomes one `crash` case and the run goes on with the cases after it; a
// worker that dies outside any case fails the run with a clear error; the journal reader
// ignores a torn last line and refuses a malformed one.
//
// This binary is its own worker: `bench_isolation_test bench ...` runs the verb with the
// test's suites (the parent re-runs /proc/self/exe exactly as skycal does).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>

#include "bench_verb.h"
#include "skycal/bench/grid.h"
#include "skycal/bench/isolated_run.h"
#include "skycal/bench/results.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "test_util.h"
#include "verb_common.h"

using namespace skycal;
using namespace skycal::bench;

namespace {

// "crashy": four cases; case n=2 aborts its process (SIGABRT: not intercepted by the
// sanitizers, so the parent sees a signal in every build). "dies-early": aborts while
// preparing, before any case.
SuiteRegistry TestRegistry() {
  SuiteRegistry r;
  Suite crashy;
  crashy.name = "crashy";
  crashy.summary = "case n=2 aborts";
  crashy.error_metric = "n / 10";
  crashy.run = [](const SuiteOptions& o) {
    std::vector<CaseResult> out;
    for (int n = 0; n < 4; ++n) {
      CaseResult c;
      c.suite = "crashy";
      c.settings = {{"n", std::to_string(n)}};
      c.name = Label(c.settings);
      c.is_default = n == 0;
      if (o.Skips(c.name)) continue;
      o.Started(c);
      if (n == 2) std::abort();
      c.time.median_ms = c.time.min_ms = c.time.max_ms = 1.0 + n;
      c.time.runs = 1;
      c.error = n / 10.0;
      o.Done(c);
      out.push_back(c);
    }
    return out;
  };
  r.Add(crashy);
  Suite early;
  early.name = "dies-early";
  early.summary = "aborts before its first case";
  early.error_metric = "none";
  early.run = [](const SuiteOptions&) -> std::vector<CaseResult> { std::abort(); };
  r.Add(early);
  return r;
}

std::string SelfExe() { return std::filesystem::read_symlink("/proc/self/exe").string(); }

}  // namespace

TEST(BenchIsolation, ACrashingCaseIsOneCaseAndTheRunGoesOn) {
  skycal::testing::ScratchDir dir("bench-isolation");
  cli::BenchOptions o;
  o.suites = "crashy";
  o.out = dir / "results";
  o.worker_executable = SelfExe();
  // The run writes its results, then fails because a case crashed.
  try {
    cli::RunBenchImpl(o, TestRegistry());
    FAIL() << "expected an error for the crashed case";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("crash"), std::string::npos) << e.what();
  }
  const nlohmann::json j = ReadJsonFile(dir / "results/results.json");
  ASSERT_EQ(j["cases"].size(), 4u);  // n=0, n=1, the crash, n=3 (run by a second worker)
  EXPECT_EQ(j["cases"][0]["case"], "n=0");
  EXPECT_EQ(j["cases"][1]["case"], "n=1");
  EXPECT_EQ(j["cases"][2]["case"], "n=2");
  EXPECT_EQ(j["cases"][2]["outcome"], "crash");
  EXPECT_NE(j["cases"][2]["message"].get<std::string>().find("signal 6"), std::string::npos) << j["cases"][2]["message"];
  EXPECT_EQ(j["cases"][3]["case"], "n=3");
  EXPECT_EQ(j["cases"][3]["outcome"], "ok");
  EXPECT_DOUBLE_EQ(j["cases"][3]["error"].get<double>(), 0.3);
}

TEST(BenchIsolation, AWorkerDyingOutsideACaseFailsTheRunClearly) {
  skycal::testing::ScratchDir dir("bench-isolation-early");
  cli::BenchOptions o;
  o.suites = "dies-early";
  o.out = dir / "results";
  o.worker_executable = SelfExe();
  try {
    cli::RunBenchImpl(o, TestRegistry());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("outside any case"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "results")) << "nothing written for a failed suite";
}

TEST(BenchIsolation, JournalIgnoresATornLastLineAndRefusesAMalformedOne) {
  skycal::testing::ScratchDir dir("bench-journal");
  const auto path = dir / "journal.jsonl";
  CaseResult c;
  c.suite = "s";
  c.settings = {{"k", "v"}};
  c.name = "k=v";
  {
    std::ofstream f(path);
    f << nlohmann::json{{"case", CaseToJson(c)}}.dump() << "\n" << "{\"start\": {\"sui";  // torn
  }
  Journal j = ReadJournal(path);
  ASSERT_EQ(j.finished.size(), 1u);
  EXPECT_EQ(j.finished[0].name, "k=v");
  EXPECT_FALSE(j.running.has_value());
  {
    std::ofstream f(path);
    f << "{not json\n" << nlohmann::json{{"case", CaseToJson(c)}}.dump() << "\n";
  }
  try {
    ReadJournal(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 1"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadJournal(dir / "absent.jsonl").finished.size(), 0u);
}

int main(int argc, char** argv) {
  // Worker mode: the parent re-runs this binary as `bench_isolation_test bench ARGS`.
  if (argc > 1 && !std::strcmp(argv[1], "bench"))
    return cli::RunVerb("bench", false, [&] { return cli::RunBenchImpl(cli::ParseBenchArgs(argc - 2, argv + 2), TestRegistry()); });
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
