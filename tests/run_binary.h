// Running the skycal binary from tests: exit code, stdout and stderr. SKYCAL_BINARY is the
// path CMake gives the test (tests/CMakeLists.txt).
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace skycal::testing {

struct ProcessResult {
  int rc = -1;
  std::string out, err;
};

inline std::string Slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Runs `skycal ARGS`, with an optional environment prefix ("VAR=value ...").
inline ProcessResult RunSkycal(const std::string& binary, const std::string& args, const std::string& env = "") {
  static int n = 0;
  const std::string base = (std::filesystem::temp_directory_path() /
                            ("skycal-run-" + std::to_string(::getpid()) + "-" + std::to_string(n++)))
                               .string();
  const std::string cmd = env + " " + binary + " " + args + " >" + base + ".out 2>" + base + ".err";
  const int status = std::system(cmd.c_str());
  ProcessResult r;
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = Slurp(base + ".out");
  r.err = Slurp(base + ".err");
  std::filesystem::remove(base + ".out");
  std::filesystem::remove(base + ".err");
  return r;
}

}  // namespace skycal::testing
