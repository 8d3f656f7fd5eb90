// No non-finite value is ever written into an image a verb outputs. Invalid input pixels
// (NaN, inf) carried through a verb are set to 0 and counted; with half output, finite
// values beyond FP16's largest (65504, e.g. the sun's disc) are counted, and the EXR writer
// clamps them to 65504 rather than writing inf. Both counts are logged with the file name.
#pragma once
#include <string>

#include "skycal/core/image.h"

namespace skycal::cli {

struct FiniteOutputCounts {
  long long non_finite = 0;    // values set to 0
  long long half_clamped = 0;  // finite values beyond +-65504 (half output only)
};

FiniteOutputCounts PrepareImageForWrite(const std::string& verb, const std::string& path, ImageRGB* image, bool half);

}  // namespace skycal::cli
