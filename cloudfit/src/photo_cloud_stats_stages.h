// The stages of FitPhotoCloudStats (skycal/cloudfit/photo_cloud_stats.h), one function each,
// so the controller reads as their sequence and each can be followed on its own.
#pragma once
#include <string>
#include <vector>

#include "skycal/cloudfit/lighting_basis_renderer.h"
#include "skycal/cloudfit/photo_cloud_stats.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/render/renderer.h"

namespace skycal::cloudfit {

// The angle-from-the-sun edges (deg) the probability records count cloud pixels in.
const std::vector<double>& ProbabilityAngleEdges();

// Logs `message` through o.log when given.
void LogStage(const PhotoCloudStatsOptions& o, const std::string& message);

// The statistics' options for `o`: its size, renders, iterations and fitted fields.
CloudStatsOptions StatsOptionsFor(const PhotoCloudStatsOptions& o);

// Solid-angle weighted mean opacity over sky pixels above `min_elevation_deg`.
double MeanOpacity(const std::vector<float>& opacity, const std::vector<float>& sky, int w, int h,
                   double min_elevation_deg);

// The cloud probability against `rendered` (a sky fit's render) as well: a pixel is cloud
// where both clear-sky expectations say so (the minimum).
std::vector<float> AlsoAgainst(const fit::Reference& ref, const ImageRGB& rendered, const std::vector<float>& p);

// Stage 1 (photo_cloud_stats_prepare.cc). Throws naming the file (see FitPhotoCloudStats).
PreparedPhoto PreparePhoto(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so, const CloudStatsPhoto& photo,
                           const fit::ReferenceFit& sky_fit, const render::Preset& preset, render::SkyRenderer& sky_renderer);

// Stage 2: the preset whose sun lights the model's clouds (o.sun). One preset lights every
// reference: with several, the photos' suns are averaged (per channel, geometric).
render::Preset CloudSunPreset(const PhotoCloudStatsOptions& o, const std::vector<PreparedPhoto>& photos,
                              const render::Preset& sky_preset);

// Stage 3 (photo_cloud_stats_coverage.cc).
CoverageMatch MatchCoverage(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so,
                            const std::vector<PreparedPhoto>& photos, const render::Preset& cloud_preset,
                            const clouds::CloudNoise& noise, clouds::CloudRenderer& renderer);

// Stage 4 (photo_cloud_stats_solve.cc). With o.sun_scale "fit" the albedo is held at
// kPhysicalCloudAlbedo and `cloud_preset`'s sun becomes the fitted one.
StatisticsFit FitStatistics(const PhotoCloudStatsOptions& o, const CloudStatsOptions& so,
                            const std::vector<PreparedPhoto>& photos, const CoverageMatch& coverage,
                            const clouds::CloudNoise& noise, clouds::CloudRenderer& renderer,
                            const render::Preset& sky_preset, render::Preset* cloud_preset);

// Stage 5 (photo_cloud_stats_image.cc), per photo r.
FitImage SynthesizeFitImage(const CloudStatsOptions& so, const PreparedPhoto& photo, const fit::Reference& ref,
                            const fit::ReferenceFit& sky_fit, const CloudStatistics& model);

// Stage 6.
CloudStatsPresetUpdate PresetUpdateFor(const PhotoCloudStatsOptions& o, const std::vector<PreparedPhoto>& photos,
                                       const StatisticsFit& fit, const render::Preset& cloud_preset,
                                       const clouds::WeatherMap& weather);

}  // namespace skycal::cloudfit
