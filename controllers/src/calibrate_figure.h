// The picture a lighting artist judges a calibration by: the photo, the game's image of the
// calibrated preset, and their difference, side by side.
#pragma once
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::controllers {

// Writes PNG `path` (atomically): photo | game | ln(game / photo) on a diverging scale of
// +-`range` (natural log; grey where `sky` < 0.5), one automatic exposure for both images
// (the photo's sky). Throws skycal::Error naming the file.
void WriteComparisonFigure(const std::string& path, const ImageRGB& photo, const ImageRGB& game,
                           const std::vector<float>& sky, double range = 0.5);

}  // namespace skycal::controllers
