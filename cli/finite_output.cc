#include "finite_output.h"

#include "verb_common.h"

namespace skycal::cli {

FiniteOutputCounts PrepareImageForWrite(const std::string& verb, const std::string& path, ImageRGB* image, bool half) {
  const FiniteOutputCounts n = MaskNonFinite(image, half);
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
