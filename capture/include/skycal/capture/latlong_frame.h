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
#include "skycal/core/row_mapping.h"

namespace skycal::capture {

struct LatLongFrame {
  ImageRGB radiance;
  std::optional<std::array<double, 3>> sun_direction;
  // Horizon-biased rows (core/row_mapping.h; `skycal resample`): written as the
  // `skycalRowMapping` attribute, and then the frame need not be 2:1.
  std::optional<RowMapping> row_mapping;
  ExrAttributes extra;  // further attributes (strings, floats, V3f) written/read verbatim
  // Further single-channel planes written after R, G, B (e.g. the clouds' transmittance);
  // not read back by ReadLatLongFrame.
  std::vector<ExrPlane> planes;
};

// Writes atomically; `half` stores 16-bit floats. Throws skycal::Error on failure.
void WriteLatLongFrame(const std::string& path, const LatLongFrame& frame, bool half = false);

// Whether a reader takes horizon-biased rows. Most readers assume core/latlong.h's uniform
// rows and refuse such a frame by name; `fit` and `resample` take them.
enum class RowMappingPolicy { kRefuse, kAccept };

// The `sunDirection` attribute (a v3f toward the sun, y up), normalised; none when absent.
// Throws skycal::Error naming `path` when it is present with another type or is not a finite
// non-zero vector.
std::optional<std::array<double, 3>> SunDirectionAttribute(const ExrAttributes& attributes, const std::string& path);

// Reads a frame. Throws skycal::Error naming the file when it is unreadable, has no
// R/G/B channels, is not 2:1 (width = 2 height, as the convention requires) unless it has a
// row mapping, carries a `sunDirection` that is not a finite non-zero vector, or a
// `skycalRowMapping` that is malformed (names the field), does not match the height, or is
// refused by `policy`. A missing `envmap` attribute is tolerated (many published skies omit
// it) and reported in `extra.strings["skycalWarning"]`.
LatLongFrame ReadLatLongFrame(const std::string& path, RowMappingPolicy policy = RowMappingPolicy::kRefuse);

}  // namespace skycal::capture
