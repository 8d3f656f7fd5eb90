#include "skycal/core/huge_pages.h"

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace skycal {
namespace {

constexpr const char* kTunable = "glibc.malloc.hugetlb";

// The selected mode of transparent huge pages, "" when the kernel has none.
std::string TransparentHugePagesMode() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(f, line)) return "";
  const size_t open = line.find('['), close = line.find(']');
  if (open == std::string::npos || close == std::string::npos || close < open) return "";
  return line.substr(open + 1, close - open - 1);
}

}  // namespace

std::string HugePageTunables(const char* tunables, const std::string& thp_mode) {
  if (tunables && std::strstr(tunables, kTunable)) return "";  // set already: by us, or by the user
  // "always": every large mapping gets huge pages anyway; "never" or none: nothing to ask for.
  if (thp_mode != "madvise") return "";
  return (tunables && *tunables ? std::string(tunables) + ":" : std::string()) + kTunable + "=1";
}

void ReexecWithHugePages(char** argv) {
  const char* off = std::getenv("SKYCAL_HUGE_PAGES");
  if (off && std::strcmp(off, "0") == 0) return;
  const std::string value = HugePageTunables(std::getenv("GLIBC_TUNABLES"), TransparentHugePagesMode());
  if (value.empty() || setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // The exec failed (no /proc): go on without; the tunable left set is read by no one.
}

}  // namespace skycal
