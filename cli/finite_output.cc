#include "finite_output.h"

#include <cmath>

#include "verb_common.h"

namespace skycal::cli {

FiniteOutputCounts PrepareImageForWrite(const std::string& verb, const std::string& path, ImageRGB* image, bool half) {
  constexpr float kHalfMax = 65504.0f;  // IEEE 754 binary16's largest finite value
  FiniteOutputCounts n;
  for (float& v : image->pixels) {
    if (!std::isfinite(v)) {
      v = 0.0f;
      ++n.non_finite;
    } else if (half && std::abs(v) > kHalfMax) {
      ++n.half_clamped;
    }
  }
  if (n.non_finite > 0) {
    Log(verb, path + ": " + std::to_string(n.non_finite) +
                  " non-finite values (NaN or inf: invalid input pixels) masked, written as 0");
  }
  if (n.half_clamped > 0) {
    Log(verb, path + ": --half: " + std::to_string(n.half_clamped) +
                  " values above 65504 (the half-float maximum, e.g. at the sun) clamped to 65504; "
                  "write float (without --half) or lower the exposure to keep them");
  }
  return n;
}

}  // namespace skycal::cli
