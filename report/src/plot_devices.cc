#include "skycal/report/plot_devices.h"

#include <dlfcn.h>
#include <plplot.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

namespace skycal::report {
namespace {
namespace fs = std::filesystem;

// PLplot's driver directory: $PLPLOT_DRV_DIR when set (plGetDrvDir reads it first), else
// the directory its pkg-config file names (CMake passes it in).
std::string DriverDirectory() {
  if (const char* env = std::getenv("PLPLOT_DRV_DIR")) return env;
#ifdef SKYCAL_PLPLOT_DRV_DIR
  return SKYCAL_PLPLOT_DRV_DIR;
#else
  return "";
#endif
}

// The module (e.g. "cairo") that lists `device` in one of DIR's .driver_info files; empty
// when none does.
std::string ModuleOf(const fs::path& dir, const std::string& device) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() != ".driver_info") continue;
    std::ifstream f(e.path());
    std::string line;
    while (std::getline(f, line)) {
      std::vector<std::string> fields;
      std::stringstream ss(line);
      for (std::string field; std::getline(ss, field, ':');) fields.push_back(field);
      if (fields.size() >= 4 && fields[0] == device) return fields[3];
    }
  }
  return "";
}

bool Check(const std::string& device, std::string* why) {
  const std::string hint = " (install Debian's plplot-driver-cairo, or point PLPLOT_DRV_DIR at its drivers directory)";
  const std::string dir = DriverDirectory();
  std::error_code ec;
  if (dir.empty() || !fs::is_directory(dir, ec)) {
    *why = "PLplot's driver directory '" + dir + "' does not exist" + hint;
    return false;
  }
  const std::string module = ModuleOf(dir, device);
  if (module.empty()) {
    *why = "PLplot's driver directory '" + dir + "' lists no " + device + " device" + hint;
    return false;
  }
  const std::string so = (fs::path(dir) / (module + ".so")).string();
  void* handle = ::dlopen(so.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (handle == nullptr) {
    const char* err = ::dlerror();
    *why = "PLplot's " + device + " module " + so + " does not load (" + (err ? err : "unknown error") + ")" + hint;
    return false;
  }
  ::dlclose(handle);
  return true;
}

std::mutex g_mutex;

// PLplot's abort messages ("aborting operation") would interleave with the verb's log and
// only repeat what PlotDeviceAvailable's `why` says; they are dropped.
void DropAbortMessage(PLCHAR_VECTOR message) { (void)message; }

int BeforePlplotExits(PLCHAR_VECTOR message) {
  std::fprintf(stderr, "skycal: PLplot is ending the process (%s); plots are optional: check PLPLOT_DRV_DIR and "
                       "Debian's plplot-driver-cairo\n", message ? message : "");
  return 1;
}

}  // namespace

void InstallPlplotHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    plsabort(DropAbortMessage);
    plsexit(BeforePlplotExits);
  });
}

bool PlotDeviceAvailable(const std::string& device, std::string* why) {
  InstallPlplotHandlers();
  static std::map<std::string, std::pair<bool, std::string>> cache;
  std::lock_guard<std::mutex> lock(g_mutex);
  auto it = cache.find(device);
  if (it == cache.end()) {
    std::string reason;
    const bool ok = Check(device, &reason);
    it = cache.emplace(device, std::make_pair(ok, reason)).first;
  }
  if (why) *why = it->second.second;
  return it->second.first;
}

}  // namespace skycal::report
