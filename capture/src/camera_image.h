// Camera brackets from JPEG, PNG and TIFF files (camera_image.cc says how and why).
#pragma once
#include <string>

#include "skycal/capture/hdr_merge.h"

namespace skycal::capture {

// The file's pixels as 8- or 16-bit RGB codes (grey expanded, alpha dropped), its EXIF
// orientation applied. Throws skycal::Error "<path>: cannot read image (...)" naming what
// failed: missing or unreadable, not JPEG/PNG/TIFF, truncated or corrupt, CMYK, float.
BracketImage DecodeCameraImage(const std::string& path);

}  // namespace skycal::capture
