// Camera brackets on a fuzzed file (capture::ReadBracketImage: JPEG through libjpeg, PNG
// through core/png_io's libpng, TIFF through libtiff, the EXIF orientation through exiv2),
// and skycal's PNG decoder on the same bytes (core::DecodePng, what the report embeds).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/core/png_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skycal;
  const std::string path = fuzz::WriteInput("bracket.img", data, size);
  fuzz::ExpectOnlySkycalErrors([&] { capture::ReadBracketImage(path); });
  fuzz::ExpectOnlySkycalErrors([&] { DecodePng(std::string(reinterpret_cast<const char*>(data), size), "fuzz.png"); });
  return 0;
}
