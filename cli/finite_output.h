// No non-finite value is ever written into an image a verb outputs: core's MaskNonFinite
// (finite_pixels.h) sets invalid input pixels (NaN, inf) to 0 and counts them and, with half
// output, the finite values the EXR writer clamps to 65504; the verb logs both counts with
// the file name. The floor under which an input frame is refused is core's
// RequireValidShare (finite_pixels.h).
#pragma once
#include <string>

#include "skycal/core/finite_pixels.h"
#include "skycal/core/image.h"

namespace skycal::cli {

FiniteOutputCounts PrepareImageForWrite(const std::string& verb, const std::string& path, ImageRGB* image, bool half);

}  // namespace skycal::cli
