// Where the binary finds the data it ships with: the bundled presets, the OCIO config, the
// reference tables. The same relative paths hold in a checkout and under an install prefix
// (`cmake --install` copies them to <prefix>/share/skycal), so a moved install keeps working.
#pragma once
#include <string>

namespace skycal {

// The data root, the first of:
//   1. $SKYCAL_DATA_DIR when set and non-empty (used as given);
//   2. <directory of /proc/self/exe>/../share/skycal when that directory exists (an installed
//      binary; preferred to 3 so an install never reads the checkout it was built from);
//   3. the source directory this binary was built from (a build tree; compiled in).
std::string DataDir();

// Which rule of DataDir() applies: "SKYCAL_DATA_DIR", "install" or "source".
std::string DataDirOrigin();

// DataDir() + "/" + relative, e.g. DataPath("datasets/presets/default_clear.json").
std::string DataPath(const std::string& relative);

}  // namespace skycal
