#include "skycal/controllers/calibrate.h"

#include <filesystem>

#include "calibrate_plan.h"
#include "calibrate_sun.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_kind.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/controllers/fit_controller.h"
#include "skycal/controllers/game_render.h"
#include "skycal/controllers/import_controller.h"
#include "skycal/core/appearance.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/staged_directory.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::controllers {
namespace fs = std::filesystem;
namespace {

// The photo's cloud probability against the model's clear sky at its sun (cloud_mask.h).
std::vector<float> CloudProbability(const ImageRGB& frame, const std::array<double, 3>& sun) {
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = frame.width;
  req.height = frame.height;
  req.sun_disc = false;
  const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(DefaultPresetPath()), req);
  return capture::EstimateCloudProbability(frame, clear, sun, {}).probability;
}

// The sun when it is plain (given, recorded, or a disc): the segmentation keeps its glare
// out of the non-sky candidates.
std::optional<std::array<double, 3>> PlainSun(const capture::LatLongFrame& f, const ImportedSun& file_sun,
                                              const CalibrateOptions& o) {
  if (o.sun_elevation_deg) return latlong::DirectionFromElevationAzimuthDeg(*o.sun_elevation_deg, *o.sun_azimuth_deg);
  if (file_sun.source == SunSource::kAttribute) return file_sun.direction;
  std::string why;
  if (const auto d = capture::DetectSun(f.radiance, &why, kCalibrateDiscContrast)) return d->direction;
  return std::nullopt;
}

}  // namespace

PhotoAnalysis AnalysePhoto(const std::string& path, const CalibrateOptions& o) {
  ImportOptions io;
  io.in_path = path;
  io.convention = std::nullopt;  // the file's envmap attribute decides (capture::ChooseConvention)
  ImportedPhoto im = ImportPhoto(io);
  PhotoAnalysis a;
  a.warnings = im.warnings;
  a.frame = std::move(im.frame);
  a.mask = capture::EstimateSkyMask(a.frame.radiance, PlainSun(a.frame, im.sun, o), {});
  std::optional<std::array<double, 3>> file_sun;
  if (im.sun.source == SunSource::kAttribute) file_sun = im.sun.direction;
  a.sun = ChoosePhotoSun(a.frame.radiance, a.mask.sky, file_sun, o);
  std::optional<double> elevation;
  std::vector<float> probability;
  if (a.sun.direction) {
    elevation = latlong::ElevationDeg(*a.sun.direction);
    probability = CloudProbability(a.frame.radiance, *a.sun.direction);
  }
  a.features = capture::MeasureSkyFeatures(a.frame.radiance, a.mask.sky, probability, elevation);
  a.features.sun_from_disc = a.sun.source == "disc";
  a.kind = capture::ClassifySky(a.features, {});
  if (!a.sun.direction && a.kind.kind == capture::SkyKind::kOvercast) {
    if (auto nominal = NominalOvercastSun(a.frame.radiance, a.mask.sky)) {
      nominal->refusal = a.sun.refusal;  // why no sun was seen, kept for the record
      a.sun = *nominal;
    }
  }
  a.cloud_probability = std::move(probability);
  return a;
}

}  // namespace skycal::controllers
