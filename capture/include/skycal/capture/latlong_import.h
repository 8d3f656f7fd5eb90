// A published equirectangular HDR sky (Blender / Poly Haven, or a frame already in the
// project's convention) turned into the project's lat-long frame (core/latlong.h): the
// direction map between the conventions and the resampling onto the project's node grid.
#pragma once
#include <array>

#include "skycal/core/image.h"

namespace skycal::capture {

// How the source image maps directions to pixels.
enum class SourceConvention {
  // Blender's equirectangular environment (Poly Haven publishes for it): Z up, pixel
  // centres at ((i + 0.5) / W, (j + 0.5) / H). See latlong_import.cc for the exact mapping.
  kBlender,
  // Already the project's (OpenEXR envmap LatLong) convention: pixel centres on the
  // nodes i / (W - 1), j / (H - 1), +Y up. Resampled only if the output size differs.
  kExr,
};
const char* ToString(SourceConvention c);

// Blender world direction (Z up) -> project direction (+Y up): (x, y, z) -> (y, z, x).
std::array<double, 3> BlenderToProjectDirection(const std::array<double, 3>& blender_dir);

// Resamples `src` (in `convention`) onto the project's node grid of out_width x out_height:
// bilinear, wrapping in longitude, clamped in latitude; each pole row is the mean of its
// finite samples (one direction, one radiance). NaN/negative source values are not
// repaired: they propagate into the pixels whose bilinear footprint touches them.
ImageRGB ResampleToProjectLatLong(const ImageRGB& src, SourceConvention convention, int out_width, int out_height);

}  // namespace skycal::capture
