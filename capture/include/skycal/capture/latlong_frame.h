// A lat-long frame on disk: an OpenEXR file of linear RGB radiance (cd/m^2 per channel,
// scene-linear Rec.709) in the project's convention (core/latlong.h), carrying the standard
// `envmap` attribute (ENVMAP_LATLONG) and, when known, `sunDirection` (V3f, unit vector
// toward the sun in the lat-long frame). Rendered skies and reference frames share it.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/exr_io.h"
#include "skycal/core/image.h"

namespace skycal::capture {

struct LatLongFrame {
  ImageRGB radiance;
  std::optional<std::array<double, 3>> sun_direction;
  ExrAttributes extra;  // further attributes (strings, floats, V3f) written/read verbatim
  // Further single-channel planes written after R, G, B (e.g. the clouds' transmittance);
  // not read back by ReadLatLongFrame.
  std::vector<ExrPlane> planes;
};

// Writes atomically; `half` stores 16-bit floats. Throws skycal::Error on failure.
void WriteLatLongFrame(const std::string& path, const LatLongFrame& frame, bool half = false);

// Reads a frame. Throws skycal::Error naming the file when it is unreadable, has no
// R/G/B channels, is not 2:1 (width = 2 height, as the convention requires), or carries a
// `sunDirection` that is not a finite non-zero vector. A missing `envmap` attribute is
// tolerated (many published skies omit it) and reported in `extra.strings["skycalWarning"]`.
LatLongFrame ReadLatLongFrame(const std::string& path);

}  // namespace skycal::capture
