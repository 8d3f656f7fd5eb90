// The verb's results files: DIR/results.json (machine, commit, date, options, per suite
// its Pareto front and plots, every case) and DIR/results.csv (one row per case, the same
// numbers flat, for a spreadsheet). The JSON is what `bench --compare` reads back.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/bench/case_result.h"

namespace skycal::bench {

inline constexpr const char* kResultsSchema = "skycal-bench-results";
inline constexpr int kResultsVersion = 1;

struct MachineInfo {
  std::string cpu_model;      // /proc/cpuinfo "model name" ("unknown" elsewhere)
  int cores = 0;              // std::thread::hardware_concurrency
  std::string vulkan_device;  // the Vulkan renderer's Describe(), or why there is none
  std::string commit;         // `git rev-parse HEAD` of the source tree, else the configure-time commit
  bool commit_dirty = false;  // uncommitted changes in the source tree when measured
  std::string date_utc;       // ISO 8601, when the run started
  std::string skycal_version;
  nlohmann::json ToJson() const;
};

// `vulkan_device` as the caller found it (creating a renderer is the suites' business).
MachineInfo DescribeMachine(const std::string& vulkan_device);

// Per suite: what it measured and where its default sits.
struct SuiteReport {
  std::string name, summary, error_metric;
  int cases = 0;
  std::vector<std::string> front;  // case names on the Pareto front (empty for non-Pareto suites)
  std::string default_case;        // empty: the suite has no single default
  bool default_on_front = false;
  std::vector<std::string> plots;  // file names in DIR
  double wall_s = 0.0;             // the suite's whole run, including preparation
};

struct Results {
  MachineInfo machine;
  nlohmann::json options = nlohmann::json::object();  // quick, repeat, suites as run
  std::vector<SuiteReport> suites;
  std::vector<CaseResult> cases;
  nlohmann::json stress = nullptr;  // the stress table (stress_table.h) when the stress suite ran
};

nlohmann::json CaseToJson(const CaseResult& c);
CaseResult CaseFromJson(const nlohmann::json& j);  // throws skycal::Error naming the field

nlohmann::json ToJson(const Results& r);
// The CSV columns, in order (the header row).
const std::vector<std::string>& CsvColumns();
std::string ToCsv(const Results& r);
// Reads a results.json value back; throws skycal::Error (`what` names the file) unless it
// has this schema and version.
Results ResultsFromJson(const nlohmann::json& j, const std::string& what);

}  // namespace skycal::bench
