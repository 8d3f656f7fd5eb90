// The sun direction a preset was fitted at, read back from the provenance `skycal fit`
// writes into the preset JSON (controllers/src/fit_controller.cc). Its own file so the export verb and the
// fuzz harness (fuzz/json_file_fuzzer.cc) share the one reader.
#pragma once
#include <string>

#include "skycal/render/irradiance.h"  // Dir3

namespace skycal::exporter {

struct SunSource {
  bool known = false;
  render::Dir3 dir{};
  std::string source, reason;  // reason: why the direction is unknown (when !known)
};

// Reads the preset JSON at `path`. A missing or malformed provenance is not an error (the
// export skips the sun-dependent outputs and says why in `reason`); an unreadable file or
// invalid JSON throws skycal::Error naming the file.
SunSource SunFromProvenance(const std::string& path);

}  // namespace skycal::exporter
