// Stage 1 of FitPhotoCloudStats: each photo's sun check, cloud probability, pixel classes
// and statistics reference; and the cloud mask's refinement before the sky fit is final.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "photo_cloud_stats_stages.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/cloudfit/photo_sun.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/latlong_resample.h"
#include "skycal/render/irradiance.h"

namespace skycal::cloudfit {
namespace {

// The photo's sun against the model's, in model units (the photo divided by the sky fit's
// exposure): the clouds' direct light is the model's sun x transmittance, and a sky fit
// without the disc does not pin it (the exposure x LUT gauge keeps the initial preset's
// sun-to-sky ratio).
PhotoSunCheck CheckPhotoSun(const fit::Reference& ref, const render::Preset& preset, double exposure) {
  const PhotoSun ps = MeasurePhotoSun(ref.radiance, ref.sun_dir);
  const render::Rgb model = render::SunIlluminanceAtGround(preset, ref.sun_dir);
  PhotoSunCheck s;
  for (int c = 0; c < 3; ++c) {
    s.photo_lux_model_units[c] = ps.illuminance[c] / exposure;
    s.model_lux[c] = model[c];
    s.photo_over_model[c] = ps.illuminance[c] / exposure / model[c];
  }
  s.disc_pixels = ps.disc_pixels;
  s.peak_over_background = ps.peak / std::max(ps.background[1], 1e-30);
  s.clipped = ps.clipped();
  s.direct_to_diffuse = ps.direct_to_diffuse();
  s.clean_disc = ps.clean_disc();
  s.saturated = ps.saturated();
  return s;
}

// The probability the statistics use: the caller's, refined against the sky fit's render
// when o.probability is "fitted" and that fit matches its clear pixels (not when the caller
// refined it already).
void ChooseProbability(const PhotoCloudStatsOptions& o, const CloudStatsPhoto& photo, const fit::ReferenceFit& sky_fit,
                       PreparedPhoto* d) {
  const fit::Reference& ref = *photo.ref;
  d->probability = photo.cloud_probability;
  CloudProbabilityRecord& rec = d->probability_record;
  rec.expectation = o.probability;
  rec.sun_angle_edges_deg = ProbabilityAngleEdges();
  rec.initial_cloud_pixels_by_sun_angle = CloudPixelsBySunAngle(d->probability, ref, ProbabilityAngleEdges());
  // A sky fit that misses its own clear pixels by more than half (an overcast frame: `city`,
  // 536% on the few it had) is no clear-sky expectation: the initial probability stays.
  rec.sky_fit_clear_rel_rmse = sky_fit.errors.rel_rmse;
  const bool refine = o.probability == "fitted" && rec.sky_fit_clear_rel_rmse <= kMaxSkyFitRelForProbability &&
                      !photo.refined;
  rec.refined = refine || photo.refined;
  rec.refined_before = photo.refined;
  if (refine) {
    d->probability = AlsoAgainst(ref, sky_fit.rendered, d->probability);
    rec.cloud_pixels_by_sun_angle = CloudPixelsBySunAngle(d->probability, ref, ProbabilityAngleEdges());
  }
}

// Sky: what the sky fit used or left out as cloud, minus what the automatic segmentation finds
// is not sky (buildings, trees, terrain: grey like cloud in the colour test). Fills the
// whole / clear / cloud references and returns the full-size sky mask (1 sky, 0 not).
std::vector<float> ClassifyPixels(const fit::Reference& ref, PreparedPhoto* d) {
  const capture::SkyMask seg = capture::EstimateSkyMask(ref.radiance, ref.sun_dir, capture::SkyMaskOptions{});
  std::vector<float> skymask(static_cast<size_t>(ref.radiance.width) * ref.radiance.height, 0.0f);
  d->whole = ref;
  d->clear = ref;
  d->cloud = ref;
  const auto keep = fit::PixelClass::kSky, drop = fit::PixelClass::kUserMasked;
  for (size_t i = 0; i < skymask.size(); ++i) {
    const fit::PixelClass c = ref.pixel_class[i];
    const bool candidate = c == fit::PixelClass::kSky || c == fit::PixelClass::kUserMasked;
    const bool is_sky = candidate && seg.sky[i] >= 0.5f;
    d->non_sky_segmented += candidate && !is_sky;
    skymask[i] = is_sky ? 1.0f : 0.0f;
    const bool cloudy = d->probability[i] >= 0.5f;
    if (candidate) {
      d->whole.pixel_class[i] = is_sky ? keep : drop;
      d->clear.pixel_class[i] = is_sky && !cloudy ? keep : drop;
      d->cloud.pixel_class[i] = is_sky && cloudy ? keep : drop;
    }
  }
  return skymask;
}

// The statistics' reference at o.width, in model units (divided by the exposure). Before any
// march: a photo with no cloud the statistics can use (after the refinement too) is refused
// here, naming the file.
void MakeStatsReference(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so, const fit::Reference& ref,
                        double exposure, const std::vector<float>& skymask, PreparedPhoto* d) {
  // Averaged down to o.width (block means for a multiple, area weights for any other size).
  const int w = ref.radiance.width, h = ref.radiance.height, ow = o.width, oh = o.width / 2;
  CloudStatsReference& sr = d->stats_ref;
  sr.name = ref.name;
  sr.radiance = ImageRGB(ow, oh);
  sr.radiance.pixels = AreaDownsampleLatLong(ref.radiance.pixels, w, h, 3, ow, oh);
  sr.opacity = AreaDownsampleLatLong(d->probability, w, h, 1, ow, oh);
  sr.sky = AreaDownsampleLatLong(skymask, w, h, 1, ow, oh);
  for (float& v : sr.radiance.pixels) v = static_cast<float>(v / exposure);  // model units
  for (float& v : sr.sky) v = v >= 0.99f ? 1.0f : 0.0f;  // a mixed pixel is not a cloud sample
  sr.sun_dir = ref.sun_dir;
  const CloudStatistics st = ComputeCloudStatistics(sr.radiance, sr.opacity, sr.sky, sr.sun_dir, so);
  if (std::none_of(st.weight.begin(), st.weight.end(), [&](double wt) { return wt >= so.min_bin_sr; })) {
    const bool refined_here = !d->probability_record.cloud_pixels_by_sun_angle.empty();
    throw Error(ref.path + ": FitPhotoCloudStats: no cloud pixels to fit (no bin of angle from the sun x elevation x " +
                "opacity holds " + FormatNumber(so.min_bin_sr) + " sr of cloud" +
                (refined_here ? "; against the sky fit's render too: PhotoCloudStatsOptions::probability = 'initial' "
                                "uses the caller's cloud probability alone)"
                              : ")"));
  }
  d->mean_cloud_probability = MeanOpacity(sr.opacity, sr.sky, o.width, o.width / 2, so.elevation_edges_deg.front());
}

}  // namespace

const std::vector<double>& ProbabilityAngleEdges() {
  static const std::vector<double> edges = {0.0, 20.0, 45.0, 90.0, 180.0};
  return edges;
}

std::vector<long long> CloudPixelsBySunAngle(const std::vector<float>& p, const fit::Reference& ref,
                                             const std::vector<double>& edges_deg) {
  const int w = ref.radiance.width, h = ref.radiance.height;
  std::vector<long long> n(edges_deg.size() - 1, 0);
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) <= 0.0) continue;
    for (int x = 0; x < w; ++x) {
      if (!(p[static_cast<size_t>(y) * w + x] >= 0.5f)) continue;
      const auto v = latlong::PixelDirection(x, y, w, h);
      const double a =
          std::acos(std::clamp(v[0] * ref.sun_dir[0] + v[1] * ref.sun_dir[1] + v[2] * ref.sun_dir[2], -1.0, 1.0)) * 180.0 / M_PI;
      for (size_t b = 0; b + 1 < edges_deg.size(); ++b)
        if (a >= edges_deg[b] && a < edges_deg[b + 1]) ++n[b];
    }
  }
  return n;
}

double MeanOpacity(const std::vector<float>& opacity, const std::vector<float>& sky, int w, int h,
                   double min_elevation_deg) {
  double s = 0.0, n = 0.0;
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) * 180.0 / M_PI < min_elevation_deg) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (!sky.empty() && !(sky[i] >= 0.5f)) continue;
      const double om = latlong::PixelSolidAngle(x, y, w, h);
      s += om * opacity[i];
      n += om;
    }
  }
  return n > 0.0 ? s / n : 0.0;
}

std::vector<float> AlsoAgainst(const fit::Reference& ref, const ImageRGB& rendered, const std::vector<float>& p) {
  const capture::CloudMask m = capture::EstimateCloudProbability(ref.radiance, rendered, ref.sun_dir, {});
  std::vector<float> q(p.size());
  for (size_t i = 0; i < p.size(); ++i) q[i] = std::min(p[i], m.probability[i]);
  return q;
}

PreparedPhoto PreparePhoto(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so, const CloudStatsPhoto& photo,
                           const fit::ReferenceFit& sky_fit, const render::Preset& preset, render::SkyRenderer& sky_renderer) {
  const fit::Reference& ref = *photo.ref;
  const int w = ref.radiance.width;
  if (w < o.width)
    throw Error(ref.path + ": FitPhotoCloudStats: the frame is " + std::to_string(w) + " wide, narrower than " +
                "PhotoCloudStatsOptions::width = " + std::to_string(o.width) + " (the statistics average the photo down to it)");
  PreparedPhoto d;
  d.sun_check = CheckPhotoSun(ref, preset, sky_fit.exposure);
  ChooseProbability(o, photo, sky_fit, &d);
  const std::vector<float> skymask = ClassifyPixels(ref, &d);
  LogStage(o, "clouds stats: " + ref.name + ": the photo's sun / the model's (green) " +
                  FormatNumber(d.sun_check.photo_over_model[1]) + (d.sun_check.clipped ? " (clipped: a lower bound)" : ""));
  MakeStatsReference(o, so, ref, sky_fit.exposure, skymask, &d);
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = o.width;
  req.height = o.width / 2;
  req.sun_disc = false;
  d.stats_ref.clear_sky = sky_renderer.Render(preset, req);
  return d;
}

namespace {

// One reference of RefineCloudMaskAndRefitSky: the probability against the sky fit's render
// too, and the pixels the first mask took as cloud that are now clear released to the sky.
ReleasedPixels ReleaseClearedPixels(fit::Reference* ref, std::vector<float>* probability, const fit::ReferenceFit& fit) {
  std::vector<float>& p = *probability;
  ReleasedPixels rj;
  rj.name = ref->name;
  rj.sky_fit_clear_rel_rmse = fit.errors.rel_rmse;
  if (!(rj.sky_fit_clear_rel_rmse <= kMaxSkyFitRelForProbability)) return rj;
  rj.refined = true;
  const std::vector<float> refined = AlsoAgainst(*ref, fit.rendered, p);
  rj.sun_angle_edges_deg = ProbabilityAngleEdges();
  rj.initial_cloud_pixels_by_sun_angle = CloudPixelsBySunAngle(p, *ref, rj.sun_angle_edges_deg);
  const long long sky_before = ref->counts.sky + ref->counts.user_masked;
  for (size_t i = 0; i < p.size(); ++i) {
    const float q = refined[i];
    if (ref->pixel_class[i] == fit::PixelClass::kUserMasked && p[i] >= 0.5f && q < 0.5f) {
      ref->pixel_class[i] = fit::PixelClass::kSky;
      ++rj.released;
    }
    p[i] = q;
  }
  ref->counts.sky += rj.released;
  ref->counts.user_masked -= rj.released;
  rj.released_fraction = sky_before > 0 ? static_cast<double>(rj.released) / sky_before : 0.0;
  rj.cloud_pixels_by_sun_angle = CloudPixelsBySunAngle(p, *ref, rj.sun_angle_edges_deg);
  return rj;
}

}  // namespace

SkyRefit RefineCloudMaskAndRefitSky(const PhotoCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                    std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                    const std::function<void()>& refit) {
  SkyRefit out;
  if (o.probability != "fitted") {
    out.skipped = SkyRefit::Skipped::kInitialProbability;
    return out;
  }
  if (user_mask) {
    out.skipped = SkyRefit::Skipped::kUserMask;
    return out;
  }
  bool any = false;
  for (size_t r = 0; r < refs->size(); ++r) {
    out.references.push_back(ReleaseClearedPixels(&(*refs)[r], &(*probability)[r], sky.references[r]));
    any = any || out.references.back().released_fraction > kSkyRefitReleasedFraction;
  }
  if (!any) {
    out.skipped = SkyRefit::Skipped::kBelowThreshold;
    return out;
  }
  const auto t0 = std::chrono::steady_clock::now();
  refit();
  out.refitted = true;
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  LogStage(o, "clouds stats: the refined cloud mask released pixels to the sky fit: refitted the atmosphere in " +
                  FormatNumber(out.time_s) + " s");
  return out;
}

}  // namespace skycal::cloudfit
