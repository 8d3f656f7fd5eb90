// The reference-frame loaders on a fuzzed OpenEXR file: core::ReadExrChannel (one plane)
// and fit::LoadReference, which reads through capture::ReadLatLongFrame (OpenEXR via
// core::ReadExrRGB, the attributes, the 2:1 and sunDirection checks) and then classifies
// the pixels (clipping plateau, sun detection when the file has no sunDirection).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "skycal/core/exr_io.h"
#include "skycal/fit/reference.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skycal;
  const std::string path = fuzz::WriteInput("frame.exr", data, size);
  fuzz::ExpectOnlySkycalErrors([&] {
    int w = 0, h = 0;
    ReadExrChannel(path, "R", &w, &h);
  });
  fuzz::ExpectOnlySkycalErrors([&] { fit::LoadReference(path, fit::FitOptions{}); });
  return 0;
}
