// render::LoadPreset on a fuzzed preset JSON. The JSON is written beside copies of the
// bundled preset's LUT EXRs (datasets/presets/default_clear.*.exr), so inputs that keep
// the seed's LUT names get past the parameters into the LUT reads and ValidatePreset.
#include <cstddef>
#include <cstdint>
#include <filesystem>

#include "fuzz_support.h"
#include "skycal/render/preset.h"

namespace {

void CopyBundledLuts() {
  namespace fs = std::filesystem;
  const fs::path src = fs::path(SKYCAL_SOURCE_DIR) / "datasets" / "presets";
  for (const char* lut : {"mie", "rayleigh", "sun_transmittance"}) {
    const std::string name = std::string("default_clear.") + lut + ".exr";
    fs::copy_file(src / name, skycal::fuzz::ScratchDir() / name, fs::copy_options::overwrite_existing);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  CopyBundledLuts();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skycal::fuzz::WriteInput("preset.json", data, size);
  skycal::fuzz::ExpectOnlySkycalErrors([&] { skycal::render::LoadPreset(path); });
  return 0;
}
