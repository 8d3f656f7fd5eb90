// OpenEXR files of RGB radiance with the metadata skycal uses. Attributes of other
// types in a file are kept out of ExrAttributes (they are not needed), never an error.
#pragma once
#include <array>
#include <map>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal {

struct ExrAttributes {
  std::map<std::string, std::string> strings;
  std::map<std::string, float> floats;
  std::map<std::string, std::array<float, 3>> v3fs;
  bool envmap_latlong = false;  // the standard `envmap` attribute, value ENVMAP_LATLONG
  // Attributes of other types (read only): name -> OpenEXR type name, so that a reader can
  // say "attribute 'sunDirection' is a v3d" rather than "missing". Not written.
  std::map<std::string, std::string> other_types;
};

enum class ExrPixelType { kFloat, kHalf };

// Writes R, G, B channels atomically (temp file + rename). Throws skycal::Error naming the
// file on failure; no partial file is left. Half output turns finite values above 65504
// into +inf, so callers that write half choose a pre-exposure first; the report counts
// the values that overflowed.
struct ExrWriteReport {
  long long half_overflow_count = 0;  // finite floats that became +-inf in half
};
ExrWriteReport WriteExrRGB(const std::string& path, const ImageRGB& image,
                           const ExrAttributes& attributes,
                           ExrPixelType type = ExrPixelType::kFloat);

struct ExrRGB {
  ImageRGB image;
  ExrAttributes attributes;
  std::vector<std::string> channels;  // every channel name in the file
};
// Reads the R, G, B channels (as float) and the attributes. Throws skycal::Error naming
// the file and what is wrong: unreadable/truncated file, missing R/G/B channel, empty
// data window.
ExrRGB ReadExrRGB(const std::string& path);

// Extra single-channel float planes (e.g. masks) written after R, G, B, each
// width * height floats, row-major. Same atomicity and errors as WriteExrRGB.
struct ExrPlane {
  std::string name;
  std::vector<float> values;
};
ExrWriteReport WriteExrRGBWithPlanes(const std::string& path, const ImageRGB& image, const std::vector<ExrPlane>& planes,
                                     const ExrAttributes& attributes, ExrPixelType type = ExrPixelType::kFloat);
// Reads one named channel as float (width * height values); throws skycal::Error naming the
// file and the channel when it is missing.
std::vector<float> ReadExrChannel(const std::string& path, const std::string& channel, int* width, int* height);

}  // namespace skycal
