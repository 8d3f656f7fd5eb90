// `skycal import`: a published equirectangular HDR sky (any RGB(A) EXR, half or float,
// any compression) converted to a reference frame in the project's lat-long convention
// (core/latlong.h), with its provenance and, when known, its sun direction.
#pragma once
#include <array>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/latlong_import.h"

namespace skycal::cli {

// The conversion lives in capture (latlong_import.h).
using capture::BlenderToProjectDirection;
using capture::ResampleToProjectLatLong;
using capture::SourceConvention;
using capture::ToString;

SourceConvention ParseSourceConvention(const std::string& text, const std::string& option);

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

}  // namespace skycal::cli
