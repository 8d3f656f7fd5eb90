// `skycal import`: a published equirectangular HDR sky (any RGB(A) EXR, half or float,
// any compression) converted to a reference frame in the project's lat-long convention
// (core/latlong.h), with its provenance and, when known, its sun direction.
#pragma once
#include <array>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/core/image.h"

namespace skycal::cli {

// How the source image maps directions to pixels.
enum class SourceConvention {
  // Blender's equirectangular environment (Poly Haven publishes for it): Z up, pixel
  // centres at ((i + 0.5) / W, (j + 0.5) / H). See import_verb.cc for the exact mapping.
  kBlender,
  // Already the project's (OpenEXR envmap LatLong) convention: pixel centres on the
  // nodes i / (W - 1), j / (H - 1), +Y up. Resampled only if the output size differs.
  kExr,
};
SourceConvention ParseSourceConvention(const std::string& text, const std::string& option);
const char* ToString(SourceConvention c);

struct ImportOptions {
  std::string in_path;                           // required, source EXR
  std::string out_path;                          // required, *.exr
  std::optional<std::array<double, 3>> sun_dir;  // in the output (project) frame; normalised
  bool detect_sun = false;                       // capture::DetectSun on the converted frame
  double min_sun_contrast = 20.0;                // peak / median sky luminance for --detect-sun
  SourceConvention convention = SourceConvention::kBlender;
  bool half = false;                             // write half floats (default float)

  bool IsValid(std::string* why) const;
};

// Converts, writes the frame atomically and returns the JSON summary. Throws skycal::Error
// (and writes nothing) on a bad input, an unwritable output, or --detect-sun without a
// distinct sun.
nlohmann::json RunImportImpl(const ImportOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
ImportOptions ParseImportArgs(int argc, char** argv);
int RunImport(int argc, char** argv);

// Blender world direction (Z up) -> project direction (+Y up): (x, y, z) -> (y, z, x).
std::array<double, 3> BlenderToProjectDirection(const std::array<double, 3>& blender_dir);

// Resamples `src` (in `convention`) onto the project's node grid of out_width x out_height:
// bilinear, wrapping in longitude, clamped in latitude; each pole row is the mean of its
// finite samples (one direction, one radiance). NaN/negative source values are not
// repaired: they propagate into the pixels whose bilinear footprint touches them.
ImageRGB ResampleToProjectLatLong(const ImageRGB& src, SourceConvention convention, int out_width, int out_height);

}  // namespace skycal::cli
