// Numbers in messages: printf's %g with 6 significant digits ("1e+300", "0.05", "128000"),
// never std::to_string's fixed notation (301 digits for 1e300, "0.000000" for 1e-9).
#pragma once
#include <cstdio>
#include <string>

namespace skycal {

inline std::string FormatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace skycal
