#include "fit_cloud_mask.h"

#include <algorithm>

#include "skycal/capture/cloud_mask.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::controllers {

fit::FitCloudMaskEntry CloudMaskApplied::Entry() const { return {cloudy_pixels, fraction, 0.5, source}; }

std::vector<float> EstimatedCloudProbability(const ImageRGB& frame, const std::array<double, 3>& sun,
                                             const std::string& clear_preset_path, const capture::CloudMaskOptions& ramp) {
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = frame.width;
  req.height = frame.height;
  req.sun_disc = false;
  const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(clear_preset_path), req);
  return capture::EstimateCloudProbability(frame, clear, sun, ramp).probability;
}

CloudMaskApplied ApplyCloudMask(fit::Reference* ref, const std::string& clear_preset_path,
                                const capture::CloudMaskOptions& ramp) {
  const int w = ref->radiance.width, h = ref->radiance.height;
  CloudMaskApplied out;
  std::vector<float> probability;
  const ExrRGB file = ReadExrRGB(ref->path);
  if (std::find(file.channels.begin(), file.channels.end(), "mask.cloud") != file.channels.end()) {
    int cw = 0, ch = 0;
    probability = ReadExrChannel(ref->path, "mask.cloud", &cw, &ch);
    if (cw != w || ch != h) throw Error(ref->path + ": channel 'mask.cloud' is not the frame's size");
    out.source = "mask.cloud channel";
  } else {
    probability = EstimatedCloudProbability(ref->radiance, ref->sun_dir, clear_preset_path, ramp);
    out.source = "estimated: colour against the clear sky of " + clear_preset_path;
  }
  const long long sky_before = ref->counts.sky;
  for (size_t i = 0; i < ref->pixel_class.size(); ++i) {
    if (ref->pixel_class[i] != fit::PixelClass::kSky || !(probability[i] >= 0.5f)) continue;
    ref->pixel_class[i] = fit::PixelClass::kUserMasked;
    --ref->counts.sky;
    ++ref->counts.user_masked;
    ++out.cloudy_pixels;
  }
  out.fraction = sky_before > 0 ? static_cast<double>(out.cloudy_pixels) / static_cast<double>(sky_before) : 0.0;
  out.probability = std::move(probability);
  if (ref->counts.sky == 0) {
    throw Error(ref->path + ": FitControllerOptions::cloud_mask = true: every sky pixel is cloud (probability >= 0.5): nothing clear to fit");
  }
  return out;
}

}  // namespace skycal::controllers
