#include "skycal/core/data_dir.h"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace skycal {
namespace {

namespace fs = std::filesystem;

struct Resolved {
  std::string dir;
  const char* origin;
};

// <exe dir>/SKYCAL_INSTALL_DATA_FROM_BIN (compile definition, "../share/skycal" for the default
// GNUInstallDirs layout), or "" when it is absent or /proc/self/exe cannot be read.
std::string InstallDataDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return "";
  const fs::path dir = (exe.parent_path() / SKYCAL_INSTALL_DATA_FROM_BIN).lexically_normal();
  if (!fs::is_directory(dir, ec)) return "";
  std::string s = dir.string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();  // lexically_normal keeps a trailing '/'
  return s;
}

// Resolved on every call (cheap): tests and callers may set $SKYCAL_DATA_DIR at run time.
Resolved Resolve() {
  const char* env = std::getenv("SKYCAL_DATA_DIR");
  if (env != nullptr && env[0] != '\0') return {env, "SKYCAL_DATA_DIR"};
  std::string installed = InstallDataDir();
  if (!installed.empty()) return {installed, "install"};
  return {SKYCAL_SOURCE_DIR, "source"};
}

}  // namespace

std::string DataDir() { return Resolve().dir; }

std::string DataDirOrigin() { return Resolve().origin; }

std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

}  // namespace skycal
