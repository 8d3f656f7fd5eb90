#include "suite_util.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>

#include "skycal/core/error.h"

namespace skycal::bench {

double RunProcessCpuS(const std::string& who, std::vector<std::string> args) {
  std::string command;
  for (const std::string& a : args) command += (command.empty() ? "" : " ") + a;
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw Error(who + ": could not start '" + args[0] + "' (" + std::strerror(rc) + ")");
  int status = 0;
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(who + ": '" + command + "' failed (status " + std::to_string(status) + ")");
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::string SelfExecutable(const std::string& who) {
  std::error_code ec;
  const std::string exe = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec || exe.empty()) throw Error(who + ": needs /proc/self/exe (the skycal binary)");
  return exe;
}

std::string FormatG(double v, int digits) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string FormatFixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string ExtraNumber(const CaseResult& c, const std::string& key, double scale) {
  const auto it = c.extra.find(key);
  if (it == c.extra.end() || !it->is_number()) return "-";
  return FormatG(scale * it->get<double>(), 4);
}

std::string CaseTable(const std::vector<CaseResult>& cases, const std::string& error_header,
                      const std::vector<TableColumn>& columns) {
  std::string t = "| case | time ms (median; min..max) | " + error_header + " |";
  std::string rule = "|---|---|---|";
  for (const TableColumn& col : columns) {
    t += " " + col.header + " |";
    rule += "---|";
  }
  t += "\n" + rule + "\n";
  for (const CaseResult& c : cases) {
    t += "| " + c.name + (c.is_default ? " (default)" : "") + " | " + FormatG(c.time.median_ms, 4) + " (" +
         FormatG(c.time.min_ms, 3) + ".." + FormatG(c.time.max_ms, 3) + ") | " +
         (c.outcome == Outcome::kOk ? FormatG(c.error, 4) : std::string(ToString(c.outcome))) + " |";
    for (const TableColumn& col : columns) t += " " + col.value(c) + " |";
    t += "\n";
  }
  return t;
}

std::optional<CaseResult> RunCase(const std::string& suite, const Settings& settings, const Settings& defaults, int k, int n,
                   const SuiteOptions& o, const std::function<void(CaseResult&)>& body) {
  CaseResult c;
  c.suite = suite;
  c.settings = settings;
  c.name = Label(settings);
  c.is_default = !defaults.empty() && settings == defaults;
  if (o.Skips(c.name)) return std::nullopt;
  o.Started(c);
  try {
    body(c);
  } catch (const Error& e) {
    c.outcome = Outcome::kClearError;
    c.message = e.what();
  } catch (const std::exception& e) {
    c.outcome = Outcome::kCrash;
    c.message = std::string("unexpected exception: ") + e.what();
  }
  std::string line = "[" + suite + " " + std::to_string(k + 1) + (n > 0 ? "/" + std::to_string(n) : "") + "] " + c.name + ": ";
  line += FormatG(c.time.median_ms) + " ms (" + FormatG(c.time.min_ms) + ".." + FormatG(c.time.max_ms) + ", " +
          std::to_string(c.time.runs) + " runs), error " + FormatG(c.error) + ", " + ToString(c.outcome);
  if (!c.message.empty()) line += ": " + c.message;
  o.Log(line);
  o.Done(c);
  return c;
}

std::map<std::string, std::unique_ptr<render::SkyRenderer>> SkyRenderersByBackend() {
  std::map<std::string, std::unique_ptr<render::SkyRenderer>> r;
  r["cpu"] = render::CreateRenderer(render::Backend::kCpu);
  r["vulkan"] = render::CreateRenderer(render::Backend::kVulkan);
  return r;
}

std::vector<CaseResult> RunGrid(const std::string& suite, const Grid& grid, const SuiteOptions& o,
                                const std::function<void(CaseResult&)>& body) {
  const std::vector<Settings> points = grid.Expand();
  std::vector<CaseResult> out;
  for (size_t k = 0; k < points.size(); ++k)
    if (auto c = RunCase(suite, points[k], grid.Defaults(), static_cast<int>(k), static_cast<int>(points.size()), o, body))
      out.push_back(std::move(*c));
  return out;
}

}  // namespace skycal::bench
