#include "skycal/bench/isolated_run.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <csignal>
#include <fstream>
#include <iterator>
#include <memory>

#include "skycal/bench/results.h"
#include "skycal/core/error.h"

extern char** environ;

namespace skycal::bench {
namespace fs = std::filesystem;
namespace {

// A case's identity for a {"start": ...} record: what a crash report needs.
nlohmann::json StartRecord(const CaseResult& c) {
  CaseResult identity;
  identity.suite = c.suite;
  identity.name = c.name;
  identity.settings = c.settings;
  identity.is_default = c.is_default;
  identity.timed = c.timed;
  return {{"start", CaseToJson(identity)}};
}

void AppendLine(const fs::path& path, const nlohmann::json& record) {
  // Opened per record: a line is whole in the kernel before the case's body runs, so a
  // worker that dies leaves every earlier record readable.
  std::ofstream f(path, std::ios::app);
  f << record.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  f.flush();
  if (!f) throw Error(path.string() + ": cannot append to the bench journal (" + std::strerror(errno) + ")");
}

std::string DescribeEnd(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::strsignal(sig);
    return "the case killed its worker process (signal " + std::to_string(sig) + ", " + (name ? name : "unknown") + ")";
  }
  return "the case ended its worker process with exit status " + std::to_string(WEXITSTATUS(status)) +
         " (e.g. a sanitizer report or an exit() inside the case)";
}

}  // namespace

Journal ReadJournal(const fs::path& path) {
  Journal j;
  std::ifstream f(path, std::ios::binary);
  if (!f) return j;
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  size_t begin = 0;
  for (int number = 1; begin < text.size(); ++number) {
    const size_t end = text.find('\n', begin);
    const bool last_unterminated = end == std::string::npos;
    const std::string line = text.substr(begin, last_unterminated ? std::string::npos : end - begin);
    begin = last_unterminated ? text.size() : end + 1;
    if (line.empty()) continue;
    nlohmann::json record;
    try {
      record = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception& e) {
      if (last_unterminated) break;  // the worker died mid-write: that record never happened
      throw Error(path.string() + ": line " + std::to_string(number) + ": malformed bench journal record (" + e.what() + ")");
    }
    if (record.contains("start")) {
      CaseResult c = CaseFromJson(record["start"]);
      j.names.insert(c.name);
      j.running = std::move(c);
    } else if (record.contains("case")) {
      CaseResult c = CaseFromJson(record["case"]);
      j.names.insert(c.name);
      if (j.running && j.running->name == c.name) j.running.reset();
      j.finished.push_back(std::move(c));
    } else {
      throw Error(path.string() + ": line " + std::to_string(number) + ": expected a \"start\" or \"case\" record");
    }
  }
  return j;
}

void AttachJournal(SuiteOptions& o, const fs::path& path) {
  o.skip = ReadJournal(path).names;
  auto started = o.on_case_start;
  o.on_case_start = [path, started](const CaseResult& c) {
    AppendLine(path, StartRecord(c));
    if (started) started(c);
  };
  auto done = o.on_case;
  o.on_case = [path, done](const CaseResult& c) {
    AppendLine(path, {{"case", CaseToJson(c)}});
    if (done) done(c);
  };
}

bool IsolatedRunOptions::IsValid(std::string* why) const {
  if (worker_argv.empty() || worker_argv[0].empty()) {
    *why = "bench: no worker executable";
    return false;
  }
  if (journal.empty()) {
    *why = "bench: no worker journal path";
    return false;
  }
  if (max_restarts < 0) {
    *why = "bench: max_restarts must be >= 0";
    return false;
  }
  return true;
}

std::vector<CaseResult> RunSuiteIsolated(const std::string& suite, const IsolatedRunOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  std::vector<char*> argv;
  for (const std::string& a : o.worker_argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (int restarts = 0;; ++restarts) {
    pid_t pid = 0;
    const int rc = ::posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ);
    if (rc != 0) throw Error("bench: cannot start the worker " + o.worker_argv[0] + " (" + std::strerror(rc) + ")");
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0) {
      if (errno != EINTR) throw Error(std::string("bench: waiting for the worker failed (") + std::strerror(errno) + ")");
    }
    Journal j = ReadJournal(o.journal);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      if (j.running) throw Error("bench: suite " + suite + "'s worker exited normally inside case " + j.running->name);
      return j.finished;
    }
    if (!j.running)
      throw Error("bench: suite " + suite + "'s worker ended outside any case: " + DescribeEnd(status) +
                  " (its messages are above)");
    CaseResult crash = *j.running;
    crash.outcome = Outcome::kCrash;
    crash.message = DescribeEnd(status);
    AppendLine(o.journal, {{"case", CaseToJson(crash)}});
    if (o.log) o.log("[" + suite + "] " + crash.name + ": CRASH: " + crash.message + "; restarting the worker after it");
    if (restarts >= o.max_restarts)
      throw Error("bench: suite " + suite + ": more than " + std::to_string(o.max_restarts) + " crashed cases");
  }
}

}  // namespace skycal::bench
