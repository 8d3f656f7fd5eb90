// Stage 5 of FitPhotoCloudStats: the statistical fit image of a photo and its errors.
#include <algorithm>
#include <cmath>

#include "photo_cloud_stats_stages.h"
#include "skycal/core/latlong.h"

namespace skycal::cloudfit {
namespace {

// The cloud part of one sky pixel of the fit image: by its opacity-class memberships, the
// model's median radiance (times the exposure) of its bins; blends it over `pixel` (the
// atmosphere's fit) by the share of the pixel no class claims.
void BlendBinMedians(const CloudStatsOptions& so, const CloudStatistics& model, int sun_bin, int elevation_bin,
                     double probability, double exposure, float pixel[3]) {
  const int nq = static_cast<int>(so.quantiles.size());
  const int mid = nq / 2;  // the median of the default {0.25, 0.5, 0.75}
  double thin = 0.0, thick = 0.0;
  OpacityClassWeights(so, probability, &thin, &thick);
  const double weights[2] = {thin, thick};
  double clear_share = 1.0;
  double acc[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    const int bin = model.Bin(sun_bin, elevation_bin, k);
    if (weights[k] <= 0.0 || model.weight[bin] <= 0.0) continue;
    clear_share -= weights[k];
    for (int ch = 0; ch < 3; ++ch)
      acc[ch] += weights[k] * exposure * std::exp(model.log_quantile[(static_cast<size_t>(bin) * 3 + ch) * nq + mid]);
  }
  for (int ch = 0; ch < 3; ++ch) pixel[ch] = static_cast<float>(clear_share * pixel[ch] + acc[ch]);
}

}  // namespace

// Each sky pixel is the atmosphere's fit where clear and, by its cloud membership, the
// model's median radiance of its (sun angle, elevation, opacity) bin where cloud. The photo's
// own cloud map places the clouds; the lighting is the fitted one. It shows how well the
// bins' lighting predicts the photo, pixel by pixel.
FitImage SynthesizeFitImage(const CloudStatsOptions& so, const PreparedPhoto& d, const fit::Reference& ref,
                            const fit::ReferenceFit& sky_fit, const CloudStatistics& model) {
  FitImage out;
  ImageRGB& pred = out.image;
  pred = sky_fit.rendered;
  const int w = ref.radiance.width, h = ref.radiance.height;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (d.whole.pixel_class[i] != fit::PixelClass::kSky) continue;
      const auto v = latlong::PixelDirection(x, y, w, h);
      const double c = std::clamp(v[0] * ref.sun_dir[0] + v[1] * ref.sun_dir[1] + v[2] * ref.sun_dir[2], -1.0, 1.0);
      int sb = 0, eb = 0;
      if (!FindCloudBin(so, std::acos(c) * 180.0 / M_PI, latlong::Latitude(y, h) * 180.0 / M_PI, &sb, &eb)) continue;
      float pixel[3] = {pred.at(x, y, 0), pred.at(x, y, 1), pred.at(x, y, 2)};
      BlendBinMedians(so, model, sb, eb, d.probability[i], sky_fit.exposure, pixel);
      for (int ch = 0; ch < 3; ++ch) pred.at(x, y, ch) = pixel[ch];
    }
  const ImageRGB& atmosphere = sky_fit.rendered;
  out.atmosphere_whole = fit::CompareToReference(d.whole, atmosphere);
  out.atmosphere_clear = fit::CompareToReference(d.clear, atmosphere);
  out.atmosphere_cloud = fit::CompareToReference(d.cloud, atmosphere);
  out.stats_whole = fit::CompareToReference(d.whole, pred);
  out.stats_clear = fit::CompareToReference(d.clear, pred);
  out.stats_cloud = fit::CompareToReference(d.cloud, pred);
  return out;
}

}  // namespace skycal::cloudfit
