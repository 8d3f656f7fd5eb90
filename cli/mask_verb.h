// `skycal mask`: the automatic sky mask of a reference frame (capture/sky_segmentation.h):
// what is not sky (buildings, trees, terrain, the ground or mirrored lower half) found
// without hand drawing, written as an EXR `skycal fit --mask` reads (R = G = B: 1 sky,
// 0 not sky; a `confidence` channel: the per-pixel confidence in [0, 1]).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/sky_segmentation.h"

namespace skycal::cli {

struct MaskOptions {
  std::string reference_path;  // required, a lat-long reference frame (*.exr)
  std::string out_path;        // required, *.exr
  capture::SkyMaskOptions segmentation;
  bool IsValid(std::string* why) const;
};

// Writes the mask atomically and returns the JSON summary. Throws skycal::Error (nothing
// written) on a bad input or option.
nlohmann::json RunMaskImpl(const MaskOptions& options);
MaskOptions ParseMaskArgs(int argc, char** argv);
int RunMask(int argc, char** argv);

}  // namespace skycal::cli
