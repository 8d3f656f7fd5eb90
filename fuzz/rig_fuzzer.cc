// capture::ParseRigJson on a fuzzed rig description (in memory; no file is read: the rig's
// image paths are only joined to base_dir).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "skycal/capture/rig.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  skycal::fuzz::ExpectOnlySkycalErrors([&] { skycal::capture::ParseRigJson(text, "fuzz-rig.json", "/fuzz/shoot"); });
  return 0;
}
