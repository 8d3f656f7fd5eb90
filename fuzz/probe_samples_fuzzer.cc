// fit::LoadProbeSamples (the "skycal-probe-samples" file `skycal probe-extract` writes and
// `skycal fit --probe` reads): core::ReadJsonFile, then the fit's own field checks.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "skycal/fit/sky_fit.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skycal::fuzz::WriteInput("noon.probe.json", data, size);
  skycal::fuzz::ExpectOnlySkycalErrors([&] { skycal::fit::LoadProbeSamples(path); });
  return 0;
}
