// Invalid pixels in the frames the verbs and controllers read and write: the floor under
// which an input frame is degenerate and refused, and the masking of non-finite values
// before a write.
#pragma once
#include <string>

#include "skycal/core/image.h"

namespace skycal {

// At least 1% of an input frame's pixels valid. A sky frame offers its whole upper
// hemisphere (half a lat-long), and lossy-compression ringing, clipping or a partial capture
// leave far more than 1% valid; below it the result rests on a handful of pixels (a fit
// "succeeded" on 4 of 16,384) or on none (a mask of an all-NaN frame reported "0% not sky").
inline constexpr double kMinValidShare = 0.01;

// Throws skycal::Error naming the file, the counts (`valid` of `total` pixels) and `what` a
// valid pixel is, when fewer than kMinValidShare of the pixels are valid.
void RequireValidShare(const std::string& path, long long valid, long long total, const std::string& what);
// The same over an image's pixels: valid = every channel finite and the luminance > 0.
void RequireValidShare(const std::string& path, const ImageRGB& image);

// No non-finite value is ever written into an output image. Invalid input pixels (NaN, inf)
// carried through are set to 0 and counted; with half output, finite values beyond FP16's
// largest (65504, e.g. the sun's disc) are counted: the EXR writer clamps them to 65504
// rather than writing inf. The caller logs both counts with the file name.
struct FiniteOutputCounts {
  long long non_finite = 0;    // values set to 0
  long long half_clamped = 0;  // finite values beyond +-65504 (half output only)
};
FiniteOutputCounts MaskNonFinite(ImageRGB* image, bool half);

}  // namespace skycal
