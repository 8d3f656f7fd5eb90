// calibrate's analysis of a photo (calibrate_plan.h): import, sky mask, sun, kind of sky.
#include "skycal/controllers/calibrate.h"

#include "calibrate_plan.h"
#include "calibrate_sun.h"
#include "fit_cloud_mask.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_kind.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/controllers/game_render.h"
#include "skycal/controllers/import_controller.h"
#include "skycal/core/latlong.h"

namespace skycal::controllers {

PhotoAnalysis AnalysePhoto(const std::string& path, const CalibrateOptions& o) {
  ImportOptions io;
  io.in_path = path;
  io.convention = std::nullopt;  // the file's envmap attribute decides (capture::ChooseConvention)
  ImportedPhoto im = ImportPhoto(io);
  PhotoAnalysis a;
  a.warnings = im.warnings;
  a.frame = std::move(im.frame);
  // The time and place: the options', else the file's (a frame `capture` made from tagged
  // brackets carries them).
  CalibrateOptions timed = o;
  if (o.time_iso8601) {
    a.time_iso8601 = o.time_iso8601;
    a.time_source = "options";
  } else if (im.time_place.complete()) {
    timed.time_iso8601 = a.time_iso8601 = im.time_place.time_iso8601;
    timed.latitude_deg = im.time_place.latitude_deg;
    timed.longitude_deg = im.time_place.longitude_deg;
    a.time_source = "the file's " + im.time_place.source;
  }
  std::optional<std::array<double, 3>> file_sun;
  if (im.sun.source == SunSource::kAttribute) file_sun = im.sun.direction;
  // The plain sun first: the segmentation keeps its glare out of the non-sky candidates; a
  // hidden one is then looked for over the sky the segmentation found.
  const PhotoSun plain = PlainPhotoSun(a.frame.radiance, file_sun, o);
  a.mask = capture::EstimateSkyMask(a.frame.radiance, plain.direction, {});
  a.sun = plain.direction ? plain : HiddenPhotoSun(a.frame.radiance, a.mask.sky, timed, plain.refusal);
  if (a.time_source.starts_with("the file")) a.sun.source += " (" + a.time_source + ")";
  std::optional<double> elevation;
  std::vector<float> probability;
  if (a.sun.direction) {
    elevation = latlong::ElevationDeg(*a.sun.direction);
    probability = EstimatedCloudProbability(a.frame.radiance, *a.sun.direction, DefaultPresetPath());  // as the fit's cloud mask
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
