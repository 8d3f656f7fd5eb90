// The Radiance picture reader (core/radiance_io.h) on fuzzed bytes: every input is decoded or
// refused with skycal::Error, within the size limits (no allocation beyond what the bytes can
// encode), and what is decoded is finite and non-negative.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fuzz_support.h"
#include "skycal/core/radiance_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skycal;
  const std::vector<unsigned char> bytes(data, data + size);
  fuzz::ExpectOnlySkycalErrors([&] {
    const RadiancePicture p = DecodeRadiancePicture(bytes, "fuzz.hdr");
    for (float v : p.image.pixels)
      if (!std::isfinite(v) || v < 0.0f) {
        std::fprintf(stderr, "skycal fuzz: decoded value %g\n", static_cast<double>(v));
        std::abort();
      }
  });
  return 0;
}
