#include "skycal/bench/results.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <thread>

#include "skycal/core/error.h"
#include "skycal/core/version.h"

namespace skycal::bench {
namespace {

std::string CpuModel() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  }
  return "unknown";
}

// Output of `command` with trailing whitespace removed; empty on failure.
std::string CommandOutput(const std::string& command) {
  std::string out;
  if (FILE* p = ::popen(command.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    if (::pclose(p) != 0) out.clear();
  }
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return out;
}

// JSON has no NaN: a missing number is null.
nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }
double NumberOr(const nlohmann::json& j, double fallback) { return j.is_number() ? j.get<double>() : fallback; }

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string CsvNumber(double v) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

nlohmann::json MachineInfo::ToJson() const {
  return {{"cpu_model", cpu_model},  {"cores", cores},     {"vulkan_device", vulkan_device}, {"commit", commit},
          {"commit_dirty", commit_dirty}, {"date_utc", date_utc}, {"skycal_version", skycal_version}};
}

MachineInfo DescribeMachine(const std::string& vulkan_device) {
  MachineInfo m;
  m.cpu_model = CpuModel();
  m.cores = static_cast<int>(std::thread::hardware_concurrency());
  m.vulkan_device = vulkan_device;
  const std::string git = "git -C '" + std::string(SKYCAL_SOURCE_DIR) + "' ";
  m.commit = CommandOutput(git + "rev-parse HEAD 2>/dev/null");
  if (m.commit.empty()) m.commit = SKYCAL_CONFIGURE_COMMIT;  // no git at run time: the commit CMake saw
  else m.commit_dirty = !CommandOutput(git + "status --porcelain --untracked-files=no 2>/dev/null").empty();
  char buf[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  m.date_utc = buf;
  m.skycal_version = kSkycalVersion;
  return m;
}

nlohmann::json CaseToJson(const CaseResult& c) {
  nlohmann::json settings = nlohmann::json::object();
  for (const auto& [k, v] : c.settings) settings[k] = v;
  return {{"suite", c.suite},
          {"case", c.name},
          {"settings", settings},
          {"settings_order", [&] {
             nlohmann::json order = nlohmann::json::array();
             for (const auto& kv : c.settings) order.push_back(kv.first);
             return order;
           }()},
          {"default", c.is_default},
          {"time_ms", c.time.ToJson()},
          {"timed", c.timed},
          {"error", Number(c.error)},
          {"outcome", ToString(c.outcome)},
          {"message", c.message},
          {"converged", c.converged ? nlohmann::json(*c.converged) : nlohmann::json()},
          {"extra", c.extra}};
}

CaseResult CaseFromJson(const nlohmann::json& j) {
  try {
    CaseResult c;
    c.suite = j.at("suite").get<std::string>();
    c.name = j.at("case").get<std::string>();
    for (const auto& k : j.at("settings_order")) c.settings.emplace_back(k.get<std::string>(), j.at("settings").at(k.get<std::string>()).get<std::string>());
    c.is_default = j.at("default").get<bool>();
    const auto& t = j.at("time_ms");
    c.time.median_ms = t.at("median_ms").get<double>();
    c.time.min_ms = t.at("min_ms").get<double>();
    c.time.max_ms = t.at("max_ms").get<double>();
    c.time.runs = t.at("runs").get<int>();
    if (t.contains("gpu_median_ms") && t["gpu_median_ms"].is_number()) c.time.gpu_median_ms = t["gpu_median_ms"].get<double>();
    c.timed = j.value("timed", true);
    c.error = NumberOr(j.at("error"), std::nan(""));
    c.outcome = ParseOutcome(j.at("outcome").get<std::string>());
    c.message = j.value("message", "");
    if (j.contains("converged") && j["converged"].is_boolean()) c.converged = j["converged"].get<bool>();
    if (j.contains("extra")) c.extra = j["extra"];
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("bench results: a case is malformed (") + e.what() + ")");
  }
}

nlohmann::json ToJson(const Results& r) {
  nlohmann::json suites = nlohmann::json::array();
  for (const SuiteReport& s : r.suites) {
    suites.push_back({{"name", s.name},         {"summary", s.summary},
                      {"error_metric", s.error_metric}, {"cases", s.cases},
                      {"pareto_front", s.front}, {"default_case", s.default_case},
                      {"default_on_front", s.default_on_front}, {"plots", s.plots},
                      {"wall_s", s.wall_s}});
  }
  nlohmann::json cases = nlohmann::json::array();
  for (const CaseResult& c : r.cases) cases.push_back(CaseToJson(c));
  return {{"schema", kResultsSchema}, {"version", kResultsVersion}, {"machine", r.machine.ToJson()},
          {"options", r.options},     {"suites", suites},           {"stress", r.stress},
          {"cases", cases}};
}

const std::vector<std::string>& CsvColumns() {
  static const std::vector<std::string> columns = {
      "suite", "case", "default", "median_ms", "min_ms", "max_ms", "runs", "error", "error_metric",
      "outcome", "converged", "on_pareto_front", "message", "gpu_median_ms"};
  return columns;
}

std::string ToCsv(const Results& r) {
  std::ostringstream csv;
  for (size_t i = 0; i < CsvColumns().size(); ++i) csv << (i ? "," : "") << CsvColumns()[i];
  csv << "\n";
  for (const CaseResult& c : r.cases) {
    std::string metric;
    bool on_front = false;
    for (const SuiteReport& s : r.suites) {
      if (s.name != c.suite) continue;
      metric = s.error_metric;
      for (const std::string& f : s.front) on_front = on_front || f == c.name;
    }
    csv << CsvField(c.suite) << "," << CsvField(c.name) << "," << (c.is_default ? 1 : 0) << ","
        << CsvNumber(c.time.median_ms) << "," << CsvNumber(c.time.min_ms) << "," << CsvNumber(c.time.max_ms) << ","
        << c.time.runs << "," << CsvNumber(c.error) << "," << CsvField(metric) << "," << ToString(c.outcome) << ","
        << (c.converged ? (*c.converged ? "1" : "0") : "") << "," << (on_front ? 1 : 0) << "," << CsvField(c.message)
        << "," << (c.time.gpu_median_ms ? CsvNumber(*c.time.gpu_median_ms) : "") << "\n";
  }
  return csv.str();
}

Results ResultsFromJson(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object() || j.value("schema", "") != kResultsSchema)
    throw Error(what + ": not a `skycal bench` results.json (schema '" + std::string(kResultsSchema) + "' expected)");
  if (j.value("version", 0) != kResultsVersion)
    throw Error(what + ": results version " + j.value("version", nlohmann::json()).dump() + ", expected " +
                std::to_string(kResultsVersion));
  Results r;
  try {
    const auto& m = j.at("machine");
    r.machine.cpu_model = m.value("cpu_model", "");
    r.machine.cores = m.value("cores", 0);
    r.machine.vulkan_device = m.value("vulkan_device", "");
    r.machine.commit = m.value("commit", "");
    r.machine.commit_dirty = m.value("commit_dirty", false);
    r.machine.date_utc = m.value("date_utc", "");
    r.machine.skycal_version = m.value("skycal_version", "");
    r.options = j.value("options", nlohmann::json::object());
    for (const auto& c : j.at("cases")) r.cases.push_back(CaseFromJson(c));
    for (const auto& s : j.value("suites", nlohmann::json::array())) {
      SuiteReport rep;
      rep.name = s.at("name").get<std::string>();
      rep.summary = s.value("summary", "");
      rep.error_metric = s.value("error_metric", "");
      rep.cases = s.value("cases", 0);
      rep.front = s.value("pareto_front", std::vector<std::string>{});
      rep.default_case = s.value("default_case", "");
      rep.default_on_front = s.value("default_on_front", false);
      rep.plots = s.value("plots", std::vector<std::string>{});
      rep.wall_s = s.value("wall_s", 0.0);
      r.suites.push_back(std::move(rep));
    }
    if (j.contains("stress")) r.stress = j["stress"];
  } catch (const nlohmann::json::exception& e) {
    throw Error(what + ": malformed results (" + e.what() + ")");
  } catch (const Error& e) {
    throw Error(what + ": " + e.what());
  }
  return r;
}

}  // namespace skycal::bench
