// A published equirectangular HDR sky (Blender / Poly Haven, or a frame already in the
// project's convention) turned into the project's lat-long frame (core/latlong.h): the
// direction map between the conventions and the resampling onto the project's node grid.
#pragma once
#include <array>

#include "skycal/core/exr_io.h"
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

// The convention of a source when none is given: a file carrying OpenEXR's standard `envmap`
// attribute with the value LatLong (ENVMAP_LATLONG; the project writes it on every frame,
// latlong_frame.h) is in the project's convention (kExr); anything else is read as the
// equirectangular that Blender and Poly Haven publish (kBlender), which carries no envmap
// attribute. A Blender-convention file that claims envmap=latlong is thus read as kExr:
// OpenEXR's LatLong is the node-grid convention (ImfEnvmap.h: the data window's first pixel
// at latitude +pi/2, longitude +pi, its last at -pi/2, -pi: both ends on pixel centres).
SourceConvention ChooseConvention(const ExrAttributes& attributes);

// Blender world direction (Z up) -> project direction (+Y up): (x, y, z) -> (y, z, x).
std::array<double, 3> BlenderToProjectDirection(const std::array<double, 3>& blender_dir);

// Resamples `src` (in `convention`) onto the project's node grid of out_width x out_height:
// bilinear, wrapping in longitude, clamped in latitude; each pole row is the mean of its
// finite samples (one direction, one radiance). NaN/negative source values are not
// repaired: they propagate into the pixels whose bilinear footprint touches them.
ImageRGB ResampleToProjectLatLong(const ImageRGB& src, SourceConvention convention, int out_width, int out_height);

}  // namespace skycal::capture
