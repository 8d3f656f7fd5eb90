// The fit controller's cloud mask (FitControllerOptions::cloud_mask): leave the cloudy pixels
// of each reference out of the sky fit (the clear sky between the clouds is what the
// atmosphere model can match). The cloud probability is
// the frame's `mask.cloud` channel (skycal capture writes it), else estimated here the same
// way (capture/cloud_mask.h: colour against the clear sky of the bundled preset at the
// frame's sun). Pixels with probability >= 0.5 become user-masked; fit.json reports the count.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "skycal/capture/cloud_mask.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/fit/reference.h"

namespace skycal::controllers {

struct CloudMaskApplied {
  long long cloudy_pixels = 0;  // sky pixels taken out
  double fraction = 0.0;        // of the sky pixels before masking
  std::string source;           // "mask.cloud channel" or "estimated against <preset>"
  std::vector<float> probability;  // per pixel of the frame (fit --clouds stats reads it; not in fit.json)
  fit::FitCloudMaskEntry Entry() const;  // fit.json's references[i].cloud_mask
};

// The cloud probability of a lat-long frame estimated against the clear sky of the preset
// at `clear_preset_path` rendered at the frame's sun (CPU, no disc; capture/cloud_mask.h,
// with `ramp`).
std::vector<float> EstimatedCloudProbability(const ImageRGB& frame, const std::array<double, 3>& sun,
                                             const std::string& clear_preset_path,
                                             const capture::CloudMaskOptions& ramp = {});

// Reclassifies `ref` in place (an estimated probability with `ramp`). Throws skycal::Error
// naming the reference when no sky pixel is left (an overcast frame: the model has no clear
// sky to fit there).
CloudMaskApplied ApplyCloudMask(fit::Reference* ref, const std::string& clear_preset_path,
                                const capture::CloudMaskOptions& ramp = {});

}  // namespace skycal::controllers
