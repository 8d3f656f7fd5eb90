// OpenEXR files of RGB radiance with the metadata skycal uses. Attributes of other
// types in a file are kept out of ExrAttributes (they are not needed), never an error.
#pragma once
#include <array>
#include <functional>
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

// The largest image the readers accept is image.h's limit (32768 x 16384, a 32K lat-long),
// checked against the header's data window before any pixel is allocated: a damaged
// header can claim 2^31 x 2^31 pixels, and allocating what it claimed turned a 2.5 KB file
// into a 16 GiB allocation (found by fuzz/exr_frame_fuzzer). OpenEXR itself is held to
// 32768 a side and to tiles of at most 8192 x 8192, so its line-offset table and tile
// buffers are bounded too. The fuzz build lowers the pixel count (SKYCAL_EXR_MAX_PIXELS)
// so that headers near the limit stay cheap to try; the check is the same code.
#ifndef SKYCAL_EXR_MAX_PIXELS
#define SKYCAL_EXR_MAX_PIXELS (32768LL * 16384LL)
#endif
inline constexpr int kMaxExrSide = 32768;
inline constexpr long long kMaxExrPixels = SKYCAL_EXR_MAX_PIXELS;
inline constexpr int kMaxExrTileSide = 8192;

// Writes R, G, B channels atomically (temp file + rename). Throws skycal::Error naming the
// file on failure; no partial file is left. Half output clamps finite values beyond 65504
// (FP16's largest) to +-65504, never +-inf, and counts them; a name ending in another
// format's extension (.png, .json, ...) is refused.
struct ExrWriteReport {
  long long half_overflow_count = 0;  // finite floats clamped to +-65504 in half
};
ExrWriteReport WriteExrRGB(const std::string& path, const ImageRGB& image,
                           const ExrAttributes& attributes,
                           ExrPixelType type = ExrPixelType::kFloat);

struct ExrRGB {
  ImageRGB image;
  ExrAttributes attributes;
  std::vector<std::string> channels;  // every channel name in the file
};
// True when the file starts with OpenEXR's magic number (20000630, little-endian); false for
// any other file or one that cannot be read (the reader then says why).
bool IsOpenExrFile(const std::string& path);
// Reads the R, G, B channels (as float) and the attributes. Throws skycal::Error naming
// the file and what is wrong: unreadable/truncated file, missing R/G/B channel, empty
// data window, an image larger than the limits above (the message gives its size).
ExrRGB ReadExrRGB(const std::string& path);
// The same, calling `check_size(width, height)` on the header's data window before any
// pixel is allocated: a reader with a tighter rule than the limits above (a weather map is
// at most 4096 a side) refuses a file by its header, not after reading 6 GiB of it. The
// check throws skycal::Error to refuse.
ExrRGB ReadExrRGB(const std::string& path, const std::function<void(int width, int height)>& check_size);

// The header alone: the data window's size and the attributes, no pixel read (a batch
// checks thousands of frames' sizes, sun directions and times before fitting any). Same
// errors and limits as ReadExrRGB, R/G/B channels included.
struct ExrHeaderInfo {
  int width = 0, height = 0;
  ExrAttributes attributes;
};
ExrHeaderInfo ReadExrHeader(const std::string& path);

// Extra single-channel float planes (e.g. masks) written after R, G, B, each
// width * height floats, row-major. Same atomicity and errors as WriteExrRGB.
struct ExrPlane {
  std::string name;
  std::vector<float> values;
};
ExrWriteReport WriteExrRGBWithPlanes(const std::string& path, const ImageRGB& image, const std::vector<ExrPlane>& planes,
                                     const ExrAttributes& attributes, ExrPixelType type = ExrPixelType::kFloat);
// Reads one named channel as float (width * height values); throws skycal::Error naming the
// file and the channel when it is missing; same size limits as ReadExrRGB.
std::vector<float> ReadExrChannel(const std::string& path, const std::string& channel, int* width, int* height);

}  // namespace skycal
