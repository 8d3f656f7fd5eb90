// The JSON the benchmarks would read, had they any: bench/ only writes its results, so this
// harness fuzzes the project's remaining JSON reader instead: core::ReadJsonFile and the
// export verb's provenance reader (export/export_sun.h: the sun direction a fitted preset
// carries), which walks the document with its own checks.
#include <cstddef>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "skycal/export/export_sun.h"
#include "fuzz_support.h"
#include "skycal/core/json_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skycal::fuzz::WriteInput("fitted.json", data, size);
  skycal::fuzz::ExpectOnlySkycalErrors([&] { skycal::ReadJsonFile(path); });
  skycal::fuzz::ExpectOnlySkycalErrors([&] { skycal::exporter::SunFromProvenance(path); });
  return 0;
}
