#include "bench_verb.h"

#include "report_verb.h"

#include <sys/prctl.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <optional>

#include "command_line.h"
#include "skycal/bench/compare.h"
#include "skycal/bench/isolated_run.h"
#include "skycal/bench/pareto.h"
#include "skycal/bench/plot.h"
#include "skycal/bench/results.h"
#include "skycal/bench/stress_table.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/report/plot_devices.h"
#include "skycal/render/renderer.h"
#include "skycal/core/staged_directory.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;
namespace {

std::string VulkanDevice() {
  try {
    return render::CreateRenderer(render::Backend::kVulkan)->Describe();
  } catch (const Error& e) {
    return std::string("none (") + e.what() + ")";
  }
}

// A point's label on the plot: the settings that differ from the default ("default" for it).
std::string ShortLabel(const bench::CaseResult& c, const bench::Settings& defaults) {
  std::string label;
  for (size_t i = 0; i < c.settings.size() && i < defaults.size(); ++i)
    if (c.settings[i].second != defaults[i].second)
      label += (label.empty() ? "" : " ") + c.settings[i].first + "=" + c.settings[i].second;
  return label.empty() ? std::string() : label;
}

nlohmann::json Compare(const BenchOptions& o) {
  bench::CompareOptions co;
  co.noise_floor = o.noise_floor;
  const bench::Results a = bench::ResultsFromJson(ReadJsonFile(o.compare[0]), o.compare[0]);
  const bench::Results b = bench::ResultsFromJson(ReadJsonFile(o.compare[1]), o.compare[1]);
  const bench::Comparison c = bench::Compare(a, b, co);
  std::cerr << c.ToText();
  if (a.machine.cpu_model != b.machine.cpu_model || a.machine.cores != b.machine.cores)
    Log("bench", "warning: the runs are from different machines ('" + a.machine.cpu_model + "' vs '" + b.machine.cpu_model +
                     "'): ratios compare machines as much as commits");
  nlohmann::json j = c.ToJson();
  if (c.Regressed()) {
    Log("bench", "regression: " + std::to_string(c.slower) + " case(s) slower beyond the noise, " +
                     std::to_string(c.error_worse) + " with a larger error, " + std::to_string(c.outcome_worse) +
                     " with a worse outcome (exit 1)");
    j["verb_failed"] = true;
  }
  return j;
}

// One suite's Pareto front, where its default sits, and its plot (DIR/<suite>_pareto.png
// and .svg) from its cases; fills rep's front, default and plots. `rep` carries the
// suite's name and summary.
void AnalyseSuite(const std::string& error_label, const std::vector<bench::CaseResult>& cases,
                  const bench::MachineInfo& machine, bool quick, const fs::path& dir, bench::SuiteReport* rep) {
  std::vector<bench::TimeError> points;
  bench::ParetoPlot plot;
  int default_index = -1;
  bench::Settings defaults;
  for (const bench::CaseResult& c : cases)
    if (c.is_default) defaults = c.settings;
  for (const bench::CaseResult& c : cases) {
    const bool usable = c.outcome == bench::Outcome::kOk;
    points.push_back({usable ? c.time.median_ms : NAN, usable ? c.error : NAN});
  }
  // Within 10% in time (the compare noise floor: quick cases run once) or 1% in error
  // two cases count as equal.
  const bench::ParetoTolerance tolerance{0.10, 0.01};
  rep->front.clear();
  for (int i : bench::ParetoFront(points, tolerance)) rep->front.push_back(cases[i].name);
  // The plot shows the usable cases only.
  for (size_t i = 0; i < cases.size(); ++i) {
    if (!std::isfinite(points[i].time) || !std::isfinite(points[i].error)) continue;
    if (cases[i].is_default) default_index = static_cast<int>(plot.cases.size());
    plot.cases.push_back(&cases[i]);
    plot.labels.push_back(cases[i].is_default ? std::string() : ShortLabel(cases[i], defaults));
  }
  std::vector<bench::TimeError> shown;
  for (const bench::CaseResult* c : plot.cases) shown.push_back({c->time.median_ms, c->error});
  plot.front = bench::ParetoFront(shown, tolerance);
  plot.default_index = default_index;
  plot.title = rep->name + ": " + rep->summary;
  plot.subtitle = machine.cpu_model + ", " + std::to_string(machine.cores) + " cores; commit " +
                  machine.commit.substr(0, 10) + (quick ? "; --quick" : "");
  plot.error_label = error_label;
  rep->default_case.clear();
  rep->default_on_front = false;
  for (const bench::CaseResult& c : cases) {
    if (!c.is_default) continue;
    rep->default_case = c.name;
    for (const std::string& f : rep->front) rep->default_on_front = rep->default_on_front || f == c.name;
  }
  rep->plots.clear();
  if (!plot.cases.empty()) {
    const std::string stem = rep->name + "_pareto";
    std::string why;
    if (report::PlotDeviceAvailable("pngcairo", &why) && report::PlotDeviceAvailable("svgcairo", &why)) {
      bench::WriteParetoPlot(plot, dir / (stem + ".png"), dir / (stem + ".svg"));
      rep->plots = {stem + ".png", stem + ".svg"};
    } else {
      Log("bench", rep->name + ": plots skipped, the Pareto plot is left out: " + why + "; the results are complete");
    }
  }
  Log("bench", rep->name + ": " + std::to_string(rep->front.size()) + " of " + std::to_string(cases.size()) +
                   " cases on the Pareto front; default " +
                   (rep->default_case.empty() ? std::string("not in this grid")
                                              : (rep->default_on_front ? "on the front" : "DOMINATED")));
}

// The stress table of `results` (if it has stress cases) as DIR/stress.md and in results.
bool WriteStressTable(bench::Results* results, const StagedDirectory& out) {
  const std::vector<bench::StressArea> table = bench::StressTable(results->cases);
  if (table.empty()) return false;
  results->stress = bench::StressTableToJson(table);
  WriteFileAtomically(out / "stress.md", "# skycal bench --suite stress\n\n" + bench::StressTableToText(table));
  std::cerr << bench::StressTableToText(table);
  return true;
}

// --replot: an earlier run's results.json -> its Pareto fronts and plots redrawn by this
// build (after a change to the plotting or the front's tolerance), into a new directory.
nlohmann::json Replot(const BenchOptions& o, const bench::SuiteRegistry& registry) {
  bench::Results results = bench::ResultsFromJson(ReadJsonFile(o.replot), o.replot);
  StagedDirectory out(o.out, "--out", "bench", {{"--replot", o.replot}});
  const bool quick = results.options.value("quick", false);
  for (bench::SuiteReport& rep : results.suites) {
    std::vector<bench::CaseResult> cases;
    for (const bench::CaseResult& c : results.cases)
      if (c.suite == rep.name) cases.push_back(c);
    const bench::Suite* suite = registry.Find(rep.name);
    if (suite && suite->markdown && !cases.empty())
      WriteFileAtomically(out / (suite->name + ".md"), suite->markdown(cases));
    const bool pareto = suite ? suite->pareto : !rep.plots.empty();
    if (!pareto || cases.empty()) continue;
    const std::string label = suite && !suite->error_axis.empty() ? suite->error_axis : rep.error_metric;
    AnalyseSuite(label, cases, results.machine, quick, out.staging(), &rep);
  }
  WriteStressTable(&results, out);
  WriteJsonFileAtomically(out / "results.json", bench::ToJson(results));
  WriteFileAtomically(out / "results.csv", bench::ToCsv(results));
  out.Commit();
  Log("bench", "redrew " + o.replot + " into " + o.out);
  nlohmann::json summary = {{"out", o.out}, {"replot", o.replot}};
  for (const bench::SuiteReport& s : results.suites)
    summary["suites"].push_back({{"name", s.name}, {"pareto_front", s.front}, {"default_on_front", s.default_on_front},
                                 {"plots", s.plots}});
  return summary;
}

// A suite's options from the verb's (sizes, repeats, the log) with its scratch directory;
// throws skycal::Error when invalid.
bench::SuiteOptions SuiteOptionsFor(const BenchOptions& o, const fs::path& scratch) {
  bench::SuiteOptions so;
  so.quick = o.quick;
  so.repeat = o.repeat;
  so.verb_logs = o.verb_logs;
  so.scratch = scratch;
  so.log = [](const std::string& line) { Log("bench", line); };
  std::string why;
  if (!so.IsValid(&why)) throw Error(why);
  return so;
}

// The worker's side of an isolated run: the one suite, journaled; the parent collects.
nlohmann::json RunWorker(const BenchOptions& o, const bench::SuiteRegistry& registry) {
  const std::vector<const bench::Suite*> suites = registry.Resolve(o.suites);
  if (suites.size() != 1) throw Error("--worker-journal: expected exactly one --suite");
  bench::SuiteOptions so = SuiteOptionsFor(o, o.worker_scratch);
  bench::AttachJournal(so, o.worker_journal);
  suites[0]->run(so);
  return {{"worker", true}};
}

// A suite's cases: in a worker process (crash-isolated) or in this one.
std::vector<bench::CaseResult> RunSuite(const BenchOptions& o, const bench::Suite& suite, const bench::SuiteOptions& so) {
  if (o.worker_executable.empty()) return suite.run(so);
  bench::IsolatedRunOptions io;
  io.journal = so.scratch / "journal.jsonl";
  io.worker_argv = {o.worker_executable, "bench", "--suite", suite.name, "--worker-journal", io.journal.string(),
                    "--worker-scratch", so.scratch.string()};
  if (o.quick) io.worker_argv.push_back("--quick");
  if (o.verb_logs) io.worker_argv.push_back("--verb-logs");
  if (o.repeat > 0) io.worker_argv.insert(io.worker_argv.end(), {"--repeat", std::to_string(o.repeat)});
  io.log = so.log;
  return bench::RunSuiteIsolated(suite.name, io);
}

}  // namespace

bool BenchOptions::IsValid(std::string* why) const {
  if (!replot.empty()) {
    if (!compare.empty() || !suites.empty()) {
      *why = "--replot: runs nothing; leave out --suite and --compare";
      return false;
    }
    if (out.empty()) {
      *why = "--replot: expected --out DIR for the redrawn results";
      return false;
    }
    return true;
  }
  if (!compare.empty()) {
    if (compare.size() != 2) {
      *why = "--compare: expected two files, OLD.json NEW.json";
      return false;
    }
    if (!suites.empty() || !out.empty()) {
      *why = "--compare: runs nothing; leave out --suite and --out";
      return false;
    }
    if (!(noise_floor >= 0.0 && noise_floor < 10.0)) {
      *why = "--noise-floor: expected a fraction in [0, 10)";
      return false;
    }
    return true;
  }
  if (suites.empty()) {
    *why = "--suite: expected one or more suite names (NAME[,NAME...])";
    return false;
  }
  if (worker_journal.empty() != worker_scratch.empty()) {
    *why = "--worker-journal and --worker-scratch go together (the verb passes them to its workers)";
    return false;
  }
  if (!worker_journal.empty()) {
    if (!out.empty()) {
      *why = "--worker-journal: a worker writes no results; leave out --out";
      return false;
    }
    return repeat >= 0 && repeat <= 1000;
  }
  if (out.empty()) {
    *why = "--out: expected the results directory";
    return false;
  }
  if (repeat < 0 || repeat > 1000) {
    *why = "--repeat: expected an integer in [1, 1000]";
    return false;
  }
  return true;
}

nlohmann::json RunBenchImpl(const BenchOptions& o, const bench::SuiteRegistry& registry) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (!o.compare.empty()) return Compare(o);
  if (!o.replot.empty()) return Replot(o, registry);
  if (!o.worker_journal.empty()) {
    // A worker ends with its parent: a SIGKILLed bench must not leave workers running.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() == 1) throw Error("bench worker: the parent bench has already exited");
    return RunWorker(o, registry);
  }
  const std::vector<const bench::Suite*> suites = registry.Resolve(o.suites);
  StagedDirectory out(o.out, "--out", "bench", {});
  // Scratch for the suites' inputs (references, brackets): beside the staging directory,
  // never part of the results, removed on exit and on interruption.
  const fs::path scratch = out.staging().parent_path() / ("." + out.staging().filename().string() + "-scratch");
  TemporaryGuard scratch_guard(scratch.string());
  struct RemoveScratch {
    fs::path p;
    ~RemoveScratch() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } remove_scratch{scratch};
  fs::create_directories(scratch);

  bench::Results results;
  results.machine = bench::DescribeMachine(VulkanDevice());
  results.options = {{"suites", o.suites}, {"quick", o.quick}, {"repeat", o.repeat}};
  Log("bench", "machine: " + results.machine.cpu_model + ", " + std::to_string(results.machine.cores) + " cores, " +
                   results.machine.vulkan_device + "; commit " + results.machine.commit);
  for (const bench::Suite* suite : suites) {
    fs::create_directories(scratch / suite->name);
    const bench::SuiteOptions so = SuiteOptionsFor(o, scratch / suite->name);
    const auto t0 = std::chrono::steady_clock::now();
    Log("bench", "suite " + suite->name + ": " + suite->summary + (o.quick ? " (--quick)" : ""));
    std::vector<bench::CaseResult> cases = RunSuite(o, *suite, so);
    bench::SuiteReport rep;
    rep.name = suite->name;
    rep.summary = suite->summary;
    rep.error_metric = suite->error_metric;
    rep.cases = static_cast<int>(cases.size());
    rep.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (suite->pareto && !cases.empty())
      AnalyseSuite(suite->error_axis.empty() ? suite->error_metric : suite->error_axis, cases, results.machine, o.quick,
                   out.staging(), &rep);
    if (suite->markdown && !cases.empty()) {
      WriteFileAtomically(out / (suite->name + ".md"), suite->markdown(cases));
      Log("bench", suite->name + ": its table in " + o.out + "/" + suite->name + ".md");
    }
    results.suites.push_back(rep);
    results.cases.insert(results.cases.end(), cases.begin(), cases.end());
  }
  const bool stress = WriteStressTable(&results, out);
  WriteJsonFileAtomically(out / "results.json", bench::ToJson(results));
  WriteFileAtomically(out / "results.csv", bench::ToCsv(results));
  if (o.report) WriteVerbReport("bench", out.staging().string());
  out.Commit();
  Log("bench", "wrote " + o.out + "/results.json, results.csv" + (stress ? ", stress.md" : "") + " and the plots");

  int failed = 0;
  nlohmann::json failures = nlohmann::json::array();
  for (const bench::CaseResult& c : results.cases) {
    if (c.outcome != bench::Outcome::kNonFinite && c.outcome != bench::Outcome::kCrash) continue;
    ++failed;
    failures.push_back({{"suite", c.suite}, {"case", c.name}, {"outcome", bench::ToString(c.outcome)}, {"message", c.message}});
  }
  if (failed) {
    for (const auto& f : failures) Log("bench", "FAILED " + f.dump());
    throw Error(std::to_string(failed) + " case(s) ended with a non-finite output or a crash (listed in " + o.out +
                "/results.csv, outcome column)");
  }
  nlohmann::json summary = {{"out", o.out}, {"machine", results.machine.ToJson()}, {"stress", results.stress}};
  for (const bench::SuiteReport& s : results.suites)
    summary["suites"].push_back({{"name", s.name}, {"cases", s.cases}, {"pareto_front", s.front},
                                 {"default_case", s.default_case}, {"default_on_front", s.default_on_front},
                                 {"plots", s.plots}, {"wall_s", s.wall_s}});
  return summary;
}

BenchOptions ParseBenchArgs(int argc, char** argv) {
  // The suite names from the registry itself, so the help cannot drift from it.
  std::string names;
  for (const std::string& n : bench::BuiltinSuites().Names()) names += (names.empty() ? "" : ", ") + n;
  VerbCommandLine cl("bench",
                     "skycal bench: run time against error across the pipeline, and numerical stress\n\n"
                     "Each suite measures a grid of settings; per case the median wall time of the repeats\n"
                     "after a warm-up (with min and max) and the error against truth or a converged reference.\n"
                     "Writes DIR/results.json (machine, commit, date, cases, each suite's Pareto front),\n"
                     "DIR/results.csv, DIR/<suite>_pareto.png/.svg and, for stress, DIR/stress.md. Exit 1 when\n"
                     "any case produced a non-finite output or crashed, and when --compare finds a regression.",
                     "  skycal bench --suite NAME[,NAME...] [--quick] [--repeat N] --out DIR [--json]\n"
                     "  skycal bench --compare OLD.json NEW.json [--noise-floor F] [--json]\n"
                     "  skycal bench --replot RESULTS.json --out DIR",
                     "Suites: " + names + ".\n"
                     "--compare flags a case SLOWER when new/old median > 1 + noise, noise being the larger\n"
                     "relative spread (max - min) / median of the two runs, at least --noise-floor.");
  BenchOptions o;
  bool json = false;
  cl.Text("--suite", &o.suites, "NAMES", "comma-separated suites: " + names);
  cl.Flag("--quick", &o.quick, "CI sizes (smaller images and grids, fewer repeats)");
  cl.Integer("--repeat", &o.repeat, 1, 1000, "expected an integer in [1, 1000]", "N",
             "timed repeats per case after the warm-up (default: each suite's own, 1-11)");
  cl.Text("--out", &o.out, "DIR", "results directory, written atomically; an existing one is replaced only\n"
                                  "when it is an earlier `skycal bench` output");
  cl.List("--compare", &o.compare, "OLD.json NEW.json", "compare two results.json instead of running");
  cl.Text("--replot", &o.replot, "RESULTS.json",
          "redraw an earlier run's Pareto fronts and plots with this build, into --out (runs nothing)");
  cl.Number("--noise-floor", &o.noise_floor, "F", "--compare: relative noise floor (default 0.10)");
  cl.Flag("--verb-logs", &o.verb_logs,
          "let the verbs the suites run (capture, export, probe-extract, fit and its clouds) print their own progress lines\n"
          "(default: only the bench's one line per case)");
  bool no_report = false;
  cl.Flag("--no-report", &no_report, "do not write DIR/report.html (skycal report)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  bool in_process = false;
  cl.Flag("--in-process", &in_process,
          "run the suites in this process (default: each in a worker process, so a case that\n"
          "crashes its process is recorded as one `crash` case and the run goes on)");
  cl.Text("--worker-journal", &o.worker_journal, "FILE", "internal: a worker's journal")->group("");
  cl.Text("--worker-scratch", &o.worker_scratch, "DIR", "internal: a worker's scratch directory")->group("");
  cl.Parse(argc, argv);
  if (!in_process && o.worker_journal.empty()) {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) o.worker_executable = self.string();  // else: in-process (no /proc)
  }
  o.report = !no_report;
  return o;
}

int RunBench(int argc, char** argv) {
  return RunVerb("bench", WantsJson(argc, argv),
                 [&]() { return RunBenchImpl(ParseBenchArgs(argc, argv), bench::BuiltinSuites()); });
}

}  // namespace skycal::cli
