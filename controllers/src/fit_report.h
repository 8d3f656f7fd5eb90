// report.png of a fit: one row per reference, reference | fit | signed relative error
// (luminance) as a diverging heat map with a labelled colour scale. Reference and fit are
// tone-mapped through the same OCIO view and the same exposure so they compare directly.
#pragma once
#include <string>
#include <vector>

#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"

namespace skycal::controllers {

// Writes DIR/<ref>.reference.png, DIR/<ref>.fit.png and DIR/<ref>.error.png (at most 512
// wide) for each reference, the images `skycal report` embeds; returns their paths.
std::vector<std::string> WriteFitPanels(const std::string& dir, const std::vector<fit::Reference>& refs,
                                        const fit::FitResult& result, double error_range = 0.2);

// Writes the PNG atomically. `error_range` is the relative error shown at full colour
// (e.g. 0.2 = +-20%); masked pixels are drawn grey.
void WriteFitReport(const std::string& png_path, const std::vector<fit::Reference>& refs, const fit::FitResult& result,
                    double error_range = 0.2);

}  // namespace skycal::controllers
