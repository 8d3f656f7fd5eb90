#include "skycal/capture/capture_pipeline.h"
#include "skycal/capture/time_place.h"

#include <chrono>
#include <cmath>
#include <iostream>

#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/lens_profile.h"
#include "skycal/capture/rig.h"
#include "skycal/capture/solar_position.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/render/renderer.h"

namespace skycal::capture {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

void Log(const std::string& message) { std::cerr << "[capture] " << message << std::endl; }
// One line on the recovered response: the method auto chose and what the EMoR prior did
// (hdr_merge.h, MergeOptions::emor_prior); "" for a fixed or analytic curve.
std::string ResponseSummary(const nlohmann::json& merge_report) {
  const nlohmann::json cal = merge_report.value("response", nlohmann::json::object()).value("calibration", nlohmann::json::object());
  if (!cal.contains("method")) return "";
  std::string line = "response: " + cal["method"].get<std::string>();
  const nlohmann::json prior = cal.value("emor_prior", nlohmann::json());
  if (!prior.is_object()) return line;
  char buf[256];
  if (prior.value("used", false)) {
    const auto& moved = prior["moved_ln"];
    std::snprintf(buf, sizeof buf,
                  "; the brackets' steps leave a wiggle of %.2f stops undetermined: taken from the EMoR camera-curve prior "
                  "(it moved ln f by %.3f..%.3f)",
                  prior["undetermined_period_stops"].get<double>(), moved[0].get<double>(), moved[1].get<double>());
    return line + buf;
  }
  return line + "; EMoR prior not used: " + prior.value("why", std::string("?"));
}

// Progress lines: only with options.verbose (the bench runs the pipeline many times).
void Progress(const CaptureOptions& o, const std::string& line) {
  if (o.verbose) Log(line);
}

// The bracket-merge flags of a pixel as a 0/1 "measured well" image, RGB-replicated, so the
// same unwrap carries it into the lat-long.
ImageRGB PlaneAsImage(const std::vector<float>& plane, int w, int h) {
  ImageRGB img(w, h);
  for (size_t i = 0; i < plane.size(); ++i) img.pixels[3 * i] = img.pixels[3 * i + 1] = img.pixels[3 * i + 2] = plane[i];
  return img;
}

}  // namespace

std::array<double, 3> CaptureOptions::CameraRotationDeg() const {
  if (camera_ypr_deg) return *camera_ypr_deg;
  if (lens.model == LensModel::kLatLong) return {0.0, 0.0, 0.0};
  return {0.0, 90.0, 0.0};
}

namespace {
// The lens settings given must fit the input: refused, never silently dropped. Messages name
// CaptureOptions' fields (the CLI writes them as its flags).
bool LensFlagsFitTheInput(const CaptureOptions& o, std::string* why) {
  std::vector<std::string> given;
  if (o.lens_fov_given) given.push_back("CaptureOptions::lens_fov_given");
  if (o.lens_center_given) given.push_back("CaptureOptions::lens_center_given");
  if (o.lens_radius_given) given.push_back("CaptureOptions::lens_radius_given");
  if (o.kb_given) given.push_back("CaptureOptions::kb_given");
  if (o.vignetting_given) given.push_back("CaptureOptions::vignetting_given");
  if (!o.lens_profile.empty() && o.lens_profile != "none") given.push_back("CaptureOptions::lens_profile");
  auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& f : v) s += (s.empty() ? "" : ", ") + f;
    return s;
  };
  if (!o.rig_path.empty() && (o.lens_model_given || !given.empty() || o.camera_ypr_deg)) {
    if (o.camera_ypr_deg) given.insert(given.begin(), "CaptureOptions::camera_ypr_deg");
    if (o.lens_model_given) given.insert(given.begin(), "CaptureOptions::lens_model_given");
    *why = "CaptureOptions::rig_path = " + o.rig_path + ": the rig file gives each camera's lens and rotation; drop " +
           joined(given);
    return false;
  }
  if (o.lens.model == LensModel::kLatLong && !given.empty()) {
    *why = "CaptureOptions::lens.model = latlong: " + joined(given) +
           " describe a fisheye's image circle; a lat-long input has none (it spans 360 x 180 degrees, its "
           "centre and radius follow from its size). Drop them, or give the fisheye model";
    return false;
  }
  if (o.kb_given && o.lens.model != LensModel::kKannalaBrandt) {
    *why = std::string("CaptureOptions::kb_given: Kannala-Brandt coefficients need CaptureOptions::lens.model = "
                       "kannala-brandt (got ") + LensModelName(o.lens.model) + ")";
    return false;
  }
  return true;
}

// The place and the colour: the sun by NREL SPA needs time and place together; one colour
// source at a time.
bool PlaceAndColorFit(const CaptureOptions& o, std::string* why) {
  const bool any_place = !o.time_iso.empty() || o.latitude_deg || o.longitude_deg;
  const bool all_place = !o.time_iso.empty() && o.latitude_deg && o.longitude_deg;
  if (any_place && !all_place) {
    *why = "CaptureOptions::time_iso, CaptureOptions::latitude_deg and CaptureOptions::longitude_deg go together "
           "(the sun by NREL SPA needs all three)";
    return false;
  }
  if (!(std::abs(o.north_longitude_deg) <= 360.0)) {
    *why = "CaptureOptions::north_longitude_deg = " + FormatNumber(o.north_longitude_deg) +
           " (expected degrees in [-360, 360])";
    return false;
  }
  if (!o.chart_path.empty() && !o.color_correction_path.empty()) {
    *why = "CaptureOptions::chart_path and CaptureOptions::color_correction_path: give one (a chart image fits the "
           "correction now, a color correction file reads one skycal chart wrote)";
    return false;
  }
  if (o.chart_corners && o.chart_path.empty()) {
    *why = "CaptureOptions::chart_corners: needs CaptureOptions::chart_path (the image the corners are in)";
    return false;
  }
  if ((!o.chart_path.empty() || !o.color_correction_path.empty()) && o.input_colorspace != "lin_rec709") {
    *why = std::string(o.chart_path.empty() ? "CaptureOptions::color_correction_path" : "CaptureOptions::chart_path") +
           " with CaptureOptions::input_colorspace = " + o.input_colorspace +
           ": the chart's 3x3 already takes camera RGB to lin_rec709; drop one of them";
    return false;
  }
  return true;
}
}  // namespace

bool CaptureOptions::IsValid(std::string* why) const {
  if (brackets.empty() == rig_path.empty()) {
    *why = "give either CaptureOptions::brackets (one camera's images) or CaptureOptions::rig_path (a rig file)";
    return false;
  }
  if (!LensFlagsFitTheInput(*this, why)) return false;
  if (!brackets.empty() && brackets.size() < 2) {
    *why = "CaptureOptions::brackets: at least two exposures are needed to merge (got 1)";
    return false;
  }
  if (!exposure_times_s.empty() && exposure_times_s.size() != brackets.size()) {
    *why = "CaptureOptions::exposure_times_s: " + std::to_string(exposure_times_s.size()) + " times for " +
           std::to_string(brackets.size()) + " brackets";
    return false;
  }
  if (width < 16 || height < 8 || width > 16384 || width != 2 * height) {
    *why = "CaptureOptions::width x height = " + std::to_string(width) + "x" + std::to_string(height) +
           " (expected a 2:1 lat-long between 16x8 and 16384x8192 pixels)";
    return false;
  }
  if (out.size() < 5 || out.substr(out.size() - 4) != ".exr") {
    *why = "CaptureOptions::out = " + out + " (expected a path ending in .exr)";
    return false;
  }
  if (!PlaceAndColorFit(*this, why)) return false;
  if (!remove_stars && !(stars == StarRemovalOptions{})) {
    *why = "CaptureOptions::stars: only with CaptureOptions::remove_stars "
           "(without it no star is removed and they would do nothing)";
    return false;
  }
  if (remove_stars && !stars.IsValid(why)) return false;
  return merge.IsValid(why);
}

nlohmann::json ChartSummary(const ColorCorrection& c) {
  const nlohmann::json j = ColorCorrectionToJson(c);
  return {{"label", c.label},
          {"source", c.source},
          {"matrix", c.matrix},
          {"delta_e2000_before", {{"mean", j["delta_e2000"]["before"]["mean"]}, {"max", j["delta_e2000"]["before"]["max"]}}},
          {"delta_e2000_after", {{"mean", j["delta_e2000"]["after"]["mean"]}, {"max", j["delta_e2000"]["after"]["max"]}}},
          {"detection", c.detection.is_object() ? c.detection.value("method", std::string()) : std::string("read")}};
}

namespace {

// The chart correction of this capture, or nothing: read (--color-correction) or fitted from
// the chart image through the merge's response curve (--chart).
std::optional<ColorCorrection> CaptureColorCorrection(const CaptureOptions& o,
                                                               const std::vector<float>& response_curve) {
  if (!o.color_correction_path.empty()) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(ReadFile(o.color_correction_path));
    } catch (const nlohmann::json::exception& e) {
      throw Error("CaptureOptions::color_correction_path = " + o.color_correction_path + ": not valid JSON (" + e.what() +
                  ")");
    }
    return ColorCorrectionFromJson(j, o.color_correction_path);
  }
  if (o.chart_path.empty()) return std::nullopt;
  ChartOptions chart;
  chart.corners = o.chart_corners;
  return CorrectionFromChartImage(o.chart_path, response_curve, chart, o.chart_label);
}

// Stage 0: what is known before any heavy work: the rig's cameras, the outputs checked
// against every input, and the sun by NREL SPA (a bad time or place is refused here).
struct CapturePlan {
  std::vector<RigCamera> rig_cameras;
  std::optional<SpaResult> spa;
  SpaInput spa_input;
  // When and where (the frame's capDate, utcOffset, latitude, longitude for `calibrate`): the
  // options', else the first bracket's EXIF. Recorded only: without the frame's north the
  // EXIF's time does not place the sun here (calibrate takes the azimuth from the sky).
  TimePlace time_place;
  std::optional<LensProfile> lens_profile;
  nlohmann::json lens_profile_report;  // what was searched and found (null: not looked up)
};

// The lens profile: explicit (CaptureOptions::lens_profile; no match is an error naming the
// closest lenses) or from the first bracket's EXIF (no match: said, and on without one).
// Not for a rig or a lat-long input (no lens of theirs to correct).
void PlanLensProfile(const CaptureOptions& o, CapturePlan* plan) {
  if (o.brackets.empty() || o.lens_profile == "none" || o.lens.model == LensModel::kLatLong) return;
  const bool explicit_spec = !o.lens_profile.empty();
  LensQuery q = ReadLensQuery(o.brackets[0]);
  std::string why;
  if (explicit_spec && !ParseLensProfileSpec(o.lens_profile, &q, &why)) throw Error(why);
  if (!explicit_spec && q.camera_model.empty() && q.lens_model.empty()) {
    plan->lens_profile_report = {{"used", false}, {"reason", "no camera or lens names in the EXIF of " + o.brackets[0]}};
    return;
  }
  LensLookup found = FindLensProfile(q);
  if (!found.profile) {
    if (explicit_spec) throw Error("CaptureOptions::lens_profile = " + o.lens_profile + ": " + found.message);
    Progress(o, found.message + "; continuing without a lens profile");
    plan->lens_profile_report = {{"used", false}, {"reason", found.message}, {"candidates", found.candidates}};
    return;
  }
  plan->lens_profile_report = found.profile->ToJson();
  plan->lens_profile_report["used"] = true;
  plan->lens_profile = std::move(found.profile);
}

CapturePlan PlanCapture(const CaptureOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  CapturePlan plan;
  // Inputs first (the rig names its cameras' images): --out must replace none of them.
  std::vector<NamedPath> inputs;
  for (const auto& p : o.brackets) inputs.push_back({"CaptureOptions::brackets", p});
  if (!o.chart_path.empty()) inputs.push_back({"CaptureOptions::chart_path", o.chart_path});
  if (!o.color_correction_path.empty()) inputs.push_back({"CaptureOptions::color_correction_path", o.color_correction_path});
  if (!o.rig_path.empty()) {
    inputs.push_back({"CaptureOptions::rig_path", o.rig_path});
    plan.rig_cameras = ReadRigFile(o.rig_path);
    for (const auto& cam : plan.rig_cameras)
      inputs.push_back({"CaptureOptions::rig_path = " + o.rig_path + " camera '" + cam.name + "' image", cam.image});
  }
  RefuseOutputsOverInputs({{"CaptureOptions::out", o.out}}, inputs);
  { AtomicOutput probe(o.out); }  // fail early on an unwritable destination
  if (!o.time_iso.empty()) {
    plan.spa_input = ParseIso8601(o.time_iso, "CaptureOptions::time_iso");
    plan.spa_input.latitude_deg = *o.latitude_deg;
    plan.spa_input.longitude_deg = *o.longitude_deg;
    plan.spa = ComputeSolarPosition(plan.spa_input);
    plan.time_place = TimePlaceOf(plan.spa_input, "CaptureOptions::time_iso, latitude_deg, longitude_deg");
  } else if (!o.brackets.empty()) {
    try {
      plan.time_place = ReadExifTimePlace(o.brackets.front());
    } catch (const Error& e) {  // the merge reads the file and names what is wrong with it
      plan.time_place.why_no_time = e.what();
    }
  }
  PlanLensProfile(o, &plan);
  return plan;
}

// Stage 1's result: each camera with its HDR image and its "measured well" image.
struct CameraImages {
  std::vector<RigCamera> cameras;
  std::vector<ImageRGB> images, measured;
  double exposure_scale = 1.0;
  nlohmann::json merge_report;
  std::vector<float> response_curve;  // the merge's, for a chart image of the same camera
  nlohmann::json sources = nlohmann::json::array();
  // Camera RAW brackets: their camera RGB -> linear Rec.709 (raw_decode.h), applied by the
  // colour stage; empty for other brackets. raw: the brackets are RAW (with or without one).
  std::vector<double> raw_camera_to_rec709;
  bool raw = false;
  nlohmann::json lens_profile;  // the lens profile's lookup and what it corrected (null: none looked up)
};

// The single camera of --brackets: its lens completed from the merged image's size, and
// from the lens profile where one was found (the fields given by hand stay).
RigCamera BracketCamera(const CaptureOptions& o, int width, int height, const std::optional<LensProfile>& profile,
                        nlohmann::json* profile_report) {
  std::string why;
  RigCamera cam;
  cam.lens = o.lens;
  cam.width = width;
  cam.height = height;
  if (!o.lens_center_given) {
    cam.lens.center_x = 0.5 * (cam.width - 1);
    cam.lens.center_y = 0.5 * (cam.height - 1);
  }
  if (!o.lens_radius_given) cam.lens.radius_px = 0.5 * std::min(cam.width, cam.height);
  if (cam.lens.model == LensModel::kLatLong) cam.lens = LatLongLens(cam.width, cam.height);
  if (profile) {
    const bool distortion_corrected = (*profile_report)["applied"].value("distortion", false);
    LensFromProfile(*profile, cam.width, cam.height, distortion_corrected, o.lens_model_given, o.lens_center_given,
                    o.lens_radius_given, o.lens_fov_given, &cam.lens, &(*profile_report)["unwrap"]);
  }
  if (!cam.lens.IsValid(&why, cam.width, cam.height)) {
    throw Error("lens for the " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + " image merged from " +
                (o.brackets.empty() ? std::string("the brackets") : "'" + o.brackets[0] + "' and the other brackets") +
                (profile ? " with the lens profile " + profile->lens_maker + ":" + profile->lens_model : std::string()) +
                ": " + why);
  }
  const std::array<double, 3> ypr = o.CameraRotationDeg();
  cam.rotation = RotationFromYawPitchRollDeg(ypr[0], ypr[1], ypr[2]);
  if (cam.lens.model == LensModel::kLatLong && !o.camera_ypr_deg)
    Progress(o, "lens model latlong: camera rotation = identity (the input is already a world lat-long)");
  cam.name = "camera";
  return cam;
}

// The RAW brackets' one camera matrix (each file carries its own: they must agree, i.e.
// come from one camera), or empty (not RAW, or LibRaw knows no matrix for the camera).
std::vector<double> RawCameraMatrix(const std::vector<Bracket>& brackets) {
  const std::vector<double>& m = brackets[0].camera_to_rec709;
  for (const Bracket& b : brackets) {
    bool same = b.camera_to_rec709.size() == m.size();
    for (size_t i = 0; same && i < m.size(); ++i) same = std::abs(b.camera_to_rec709[i] - m[i]) <= 1e-6 * (1.0 + std::abs(m[i]));
    if (!same)
      throw Error(b.path + ": camera RAW colour matrix differs from " + brackets[0].path +
                  "'s; the brackets of one merge come from one camera");
  }
  return m;
}

// Stage 1b: the lens profile's vignetting, TCA and distortion on the merged radiance, each
// unless given by hand (CaptureOptions::lens.vignetting, lens.kb_k). After the merge because
// the merge is per pixel, a weighted mean of each exposure's linear estimate: vignetting
// scales every exposure of a pixel alike, so dividing the mean divides each of them (once
// instead of per bracket); the resampling of TCA and distortion moves linear values that
// agree across the exposures wherever a pixel is measured well.
void CorrectWithProfile(const CaptureOptions& o, const LensProfile& p, ImageRGB* radiance, nlohmann::json* report,
                        nlohmann::json* skipped) {
  const LensCorrections which{!o.vignetting_given, true, !o.kb_given};
  (*report)["applied"] = ApplyLensProfile(p, which, radiance, o.merge.threads);
  if (o.vignetting_given) (*report)["overridden"].push_back("vignetting: CaptureOptions::lens.vignetting given");
  if (o.kb_given) (*report)["overridden"].push_back("distortion: CaptureOptions::lens.kb_k given");
  for (const auto& m : p.missing) skipped->push_back({{"stage", "lens profile " + m.substr(0, m.find(':'))}, {"reason", m}});
  std::string applied;
  for (const char* k : {"vignetting", "tca", "distortion"})
    if ((*report)["applied"].value(k, false)) applied += std::string(applied.empty() ? "" : ", ") + k;
  Progress(o, "lens profile " + p.lens_maker + ":" + p.lens_model +
                  (p.camera_model.empty() ? std::string() : " on " + p.camera_maker + ":" + p.camera_model) + ": " +
                  (applied.empty() ? std::string("nothing applied") : applied + " corrected"));
}

// Stage 1, one camera: the brackets merged to radiance.
CameraImages MergeStage(const CaptureOptions& o, const CapturePlan& plan, nlohmann::json* skipped) {
  CameraImages r;
  nlohmann::json load_report;
  const auto brackets = LoadBrackets(o.brackets, o.exposure_times_s, 0, &load_report);
  MergeResult merged = MergeBrackets(brackets, o.merge);
  r.raw = brackets[0].image.linear;
  r.raw_camera_to_rec709 = RawCameraMatrix(brackets);
  for (const auto& w : merged.report["warnings"]) Log("merge warning: " + w.get<std::string>());
  r.exposure_scale = merged.exposure_scale;
  r.merge_report = merged.report;
  r.response_curve = merged.response_curve;
  Progress(o, "merged " + std::to_string(brackets.size()) + " brackets (" + std::to_string(merged.not_well_measured) +
                  " pixels no exposure measured well)");
  if (const std::string line = ResponseSummary(merged.report); !line.empty()) Progress(o, line);
  r.lens_profile = plan.lens_profile_report;
  if (plan.lens_profile) CorrectWithProfile(o, *plan.lens_profile, &merged.radiance, &r.lens_profile, skipped);
  const RigCamera cam =
      BracketCamera(o, merged.radiance.width, merged.radiance.height, plan.lens_profile, &r.lens_profile);
  ImageRGB measured = PlaneAsImage(merged.well_measured, cam.width, cam.height);
  if (plan.lens_profile && r.lens_profile["applied"].value("distortion", false))  // the image's geometry
    ApplyLensProfile(*plan.lens_profile, {false, false, true}, &measured, o.merge.threads);
  r.measured.push_back(std::move(measured));
  r.images.push_back(std::move(merged.radiance));
  r.cameras.push_back(cam);
  for (const auto& p : o.brackets) r.sources.push_back({{"path", p}, {"sha256", Sha256OfFile(p)}});
  return r;
}

// Stage 1, a rig: each camera's HDR EXR as it is (every pixel measured well).
CameraImages LoadRigStage(const std::vector<RigCamera>& rig_cameras, nlohmann::json* skipped) {
  CameraImages r;
  r.cameras = rig_cameras;
  for (const auto& cam : r.cameras) {
    ExrRGB exr = ReadExrRGB(cam.image);
    r.measured.push_back(PlaneAsImage(std::vector<float>(static_cast<size_t>(exr.image.width) * exr.image.height, 1.0f),
                                      exr.image.width, exr.image.height));
    r.images.push_back(std::move(exr.image));
    r.sources.push_back({{"path", cam.image}, {"sha256", Sha256OfFile(cam.image)}});
  }
  skipped->push_back({{"stage", "merge"}, {"reason", "rig: the cameras' images are HDR already"}});
  return r;
}

// Stage 2: camera space -> the working space (scene-linear Rec.709): the chart's 3x3, or OCIO.
struct ColourResult {
  std::optional<ColorCorrection> chart;
  nlohmann::json summary;
};

ColourResult ColourStage(const CaptureOptions& o, const CameraImages& cams, std::vector<ImageRGB>* images,
                         nlohmann::json* skipped) {
  ColourResult r;
  r.chart = CaptureColorCorrection(o, cams.response_curve);
  if (cams.raw && !r.chart) {
    // Camera RAW: camera RGB -> lin_rec709 by the file's own matrix (raw_decode.h).
    if (o.input_colorspace != "lin_rec709")
      throw Error("CaptureOptions::input_colorspace = " + o.input_colorspace +
                  ": the brackets are camera RAW, converted to lin_rec709 by their camera matrix; drop it");
    if (cams.raw_camera_to_rec709.size() != 9)
      throw Error("CaptureOptions::brackets: camera RAW '" + o.brackets[0] +
                  "' has no colour matrix (LibRaw knows none for the camera); give CaptureOptions::chart_path or "
                  "CaptureOptions::color_correction_path");
    Matrix3 m;
    std::copy(cams.raw_camera_to_rec709.begin(), cams.raw_camera_to_rec709.end(), m.begin());
    for (ImageRGB& img : *images) ApplyColorCorrection(m, &img);
    r.summary = {{"source", "camera RAW matrix (LibRaw rgb_cam x daylight pre_mul)"}, {"matrix", m}};
  } else if (r.chart) {
    if (cams.raw) skipped->push_back({{"stage", "raw camera matrix"}, {"reason", "replaced by the colour chart correction"}});
    for (ImageRGB& img : *images) ApplyColorCorrection(r.chart->matrix, &img);
    r.summary = ChartSummary(*r.chart);
    Log("colour chart correction (" + (o.chart_path.empty() ? o.color_correction_path : o.chart_path) +
        ") applied: chart mean CIEDE2000 " + std::to_string(r.summary["delta_e2000_before"]["mean"].get<double>()) +
        " -> " + std::to_string(r.summary["delta_e2000_after"]["mean"].get<double>()));
  } else if (o.input_colorspace != "lin_rec709") {
    for (ImageRGB& img : *images) color::ConvertColorspace(img, o.input_colorspace, "lin_rec709");
  } else {
    skipped->push_back({{"stage", "colour"}, {"reason", "input already lin_rec709"}});
  }
  return r;
}

// Stage 3: the cameras unwrapped / stitched to the lat-long, stars removed on request.
struct UnwrapResult {
  ImageRGB frame, measured_frame;
  std::vector<float> coverage;
  std::optional<StarRemovalResult> stars;
};

UnwrapResult UnwrapStage(const CaptureOptions& o, const CameraImages& cams) {
  std::vector<std::pair<RigCamera, const ImageRGB*>> views, measured_views;
  for (size_t i = 0; i < cams.cameras.size(); ++i) {
    views.push_back({cams.cameras[i], &cams.images[i]});
    measured_views.push_back({cams.cameras[i], &cams.measured[i]});
  }
  UnwrapResult r;
  r.frame = UnwrapToLatLong(views, o.width, o.height, &r.coverage);
  r.measured_frame = UnwrapToLatLong(measured_views, o.width, o.height, nullptr);
  if (o.remove_stars) {
    r.stars = RemoveStars(r.frame, o.stars);
    r.frame = std::move(r.stars->image);
    Log("removed " + std::to_string(r.stars->stars) + " stars (" + std::to_string(r.stars->pixels_replaced) +
        " pixels replaced by their neighbourhood's median)");
  }
  return r;
}

// Stage 4: the sun: SPA and detection; the camera heading from the two when both exist.
struct SunResult {
  nlohmann::json summary = nlohmann::json::object();
  std::optional<std::array<double, 3>> direction;
};

SunResult SunStage(const CaptureOptions& o, const std::optional<SpaResult>& spa, const ImageRGB& frame,
                   nlohmann::json* skipped) {
  SunResult r;
  nlohmann::json& sun = r.summary;
  if (spa) {
    r.direction = SunDirectionInFrame(*spa, o.north_longitude_deg);
    sun["spa"] = {{"zenith_deg", spa->zenith_deg}, {"azimuth_deg", spa->azimuth_deg}};
  }
  std::string detect_why;
  if (auto d = DetectSun(frame, &detect_why)) {
    sun["detected"] = {{"direction", d->direction},
                       {"elevation_deg", latlong::ElevationDeg(d->direction)},
                       {"azimuth_deg", latlong::AzimuthDeg(d->direction)},
                       {"clipped", d->clipped},
                       {"contrast", d->contrast}};
    if (spa) {
      // Heading: how far the rig's longitude 0 is from where north was assumed.
      double offset = latlong::AzimuthDeg(d->direction) - latlong::AzimuthDeg(*r.direction);
      offset = std::remainder(offset, 360.0);
      sun["camera_heading_offset_deg"] = offset;
      sun["suggested_north_longitude_deg"] = std::remainder(o.north_longitude_deg + offset, 360.0);
      Progress(o, "camera heading: the detected sun is " + std::to_string(offset) +
                      " deg of longitude from the SPA sun; CaptureOptions::north_longitude_deg = " +
                      std::to_string(sun["suggested_north_longitude_deg"].get<double>()) + " aligns them");
    } else {
      r.direction = d->direction;
    }
  } else {
    sun["detection"] = "no distinct sun: " + detect_why;
  }
  if (!r.direction)
    skipped->push_back({{"stage", "sunDirection"},
                        {"reason", "no time and place (CaptureOptions::time_iso, latitude_deg, longitude_deg) and no sun "
                                   "detected"}});
  return r;
}

// Stage 5: the mask planes: valid (covered and measured well), below the horizon, stars
// (when removed) and cloud probability (colour against the clear-sky model at this sun).
struct MaskResult {
  std::vector<ExrPlane> planes;
  long long valid_count = 0;
};

MaskResult MaskStage(const CaptureOptions& o, const UnwrapResult& u, SunResult* sun, nlohmann::json* stages,
                     nlohmann::json* skipped) {
  const size_t n = static_cast<size_t>(o.width) * o.height;
  ExrPlane valid{"mask.valid", std::vector<float>(n, 0.0f)}, below{"mask.belowHorizon", std::vector<float>(n, 0.0f)};
  MaskResult r;
  for (int y = 0; y < o.height; ++y) {
    const bool under = latlong::Latitude(y, o.height) <= 0.0;
    for (int x = 0; x < o.width; ++x) {
      const size_t i = static_cast<size_t>(y) * o.width + x;
      const bool ok = u.coverage[i] > 0.0f && u.measured_frame.pixels[3 * i] > 0.5f;
      valid.values[i] = ok ? 1.0f : 0.0f;
      below.values[i] = under ? 1.0f : 0.0f;
      r.valid_count += ok;
    }
  }
  r.planes = {valid, below};
  if (u.stars) r.planes.push_back({"mask.stars", std::vector<float>(u.stars->mask.begin(), u.stars->mask.end())});
  if (!sun->direction) {
    skipped->push_back({{"stage", "cloud mask"}, {"reason", "needs the sun direction for the clear-sky expectation"}});
    return r;
  }
  render::RenderRequest req;
  req.sun_dir = *sun->direction;
  req.width = o.width;
  req.height = o.height;
  req.sun_disc = false;
  const std::string preset =
      o.clear_sky_preset.empty() ? DataPath("datasets/presets/default_clear.json") : o.clear_sky_preset;
  const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(preset), req);
  const CloudMask cm = EstimateCloudProbability(u.frame, clear, sun->direction, {});
  r.planes.push_back({"mask.cloud", cm.probability});
  sun->summary["cloud_offset_ln_rb"] = cm.clear_offset;
  (*stages)["cloudy_pixels"] = cm.cloudy_pixels;
  return r;
}

// Stage 6's metadata: the frame's EXR attributes (sun, time and place, exposure scale,
// sources, lens, colour correction, units, version).
ExrAttributes FrameAttributes(const CaptureOptions& o, const CapturePlan& plan, const SunResult& sun,
                              const CameraImages& cams, const ColourResult& colour) {
  ExrAttributes attrs;
  attrs.envmap_latlong = true;
  if (sun.direction) {
    const std::array<double, 3>& d = *sun.direction;
    attrs.v3fs["sunDirection"] = {static_cast<float>(d[0]), static_cast<float>(d[1]), static_cast<float>(d[2])};
  }
  if (plan.spa) {
    attrs.strings["skycalCaptureTime"] = o.time_iso;
    attrs.floats["skycalLatitudeDeg"] = static_cast<float>(*o.latitude_deg);
    attrs.floats["skycalLongitudeDeg"] = static_cast<float>(*o.longitude_deg);
    const SpaInput& t = plan.spa_input;
    attrs.floats["skycalTimeOfDay"] = static_cast<float>(t.hour + t.minute / 60.0 + t.second / 3600.0);
  }
  AddTimePlaceAttributes(plan.time_place, &attrs);
  attrs.floats["skycalExposureScale"] = static_cast<float>(cams.exposure_scale);
  attrs.strings["skycalSources"] = cams.sources.dump();
  attrs.strings["skycalLens"] = o.rig_path.empty() ? std::string(LensModelName(o.lens.model)) : "rig " + o.rig_path;
  if (o.rig_path.empty()) {
    const std::array<double, 3> ypr = o.CameraRotationDeg();
    attrs.v3fs["skycalCameraRotationDeg"] = {static_cast<float>(ypr[0]), static_cast<float>(ypr[1]), static_cast<float>(ypr[2])};
  }
  if (colour.chart) attrs.strings["skycalColorCorrection"] = ColorCorrectionToJson(*colour.chart).dump();
  if (cams.lens_profile.is_object() && cams.lens_profile.value("used", false)) attrs.strings["skycalLensProfile"] = cams.lens_profile.dump();
  attrs.strings["skycalUnits"] = "relative radiance: linear / (t ISO/100 / N^2), scene-linear Rec.709";
  attrs.strings["skycalVersion"] = kSkycalVersion;
  return attrs;
}

}  // namespace

nlohmann::json RunCapturePipeline(const CaptureOptions& o) {
  const CapturePlan plan = PlanCapture(o);
  nlohmann::json stages = nlohmann::json::object(), skipped = nlohmann::json::array();
  const auto t0 = Clock::now();
  CameraImages cams = o.brackets.empty() ? LoadRigStage(plan.rig_cameras, &skipped) : MergeStage(o, plan, &skipped);
  const auto t1 = Clock::now();
  stages["merge_ms"] = Ms(t0, t1);
  if (cams.lens_profile.contains("applied")) stages["lens_profile_ms"] = cams.lens_profile["applied"]["ms"];
  const ColourResult colour = ColourStage(o, cams, &cams.images, &skipped);
  const auto t2 = Clock::now();
  stages["colour_ms"] = Ms(t1, t2);
  const UnwrapResult unwrapped = UnwrapStage(o, cams);
  const auto t3 = Clock::now();
  stages["unwrap_ms"] = Ms(t2, t3);
  SunResult sun = SunStage(o, plan.spa, unwrapped.frame, &skipped);
  const auto t4 = Clock::now();
  stages["sun_ms"] = Ms(t3, t4);
  const MaskResult masks = MaskStage(o, unwrapped, &sun, &stages, &skipped);
  const auto t_mask = Clock::now();
  stages["mask_ms"] = Ms(t4, t_mask);
  WriteExrRGBWithPlanes(o.out, unwrapped.frame, masks.planes, FrameAttributes(o, plan, sun, cams, colour));
  const auto t5 = Clock::now();
  stages["write_ms"] = Ms(t_mask, t5);
  stages["total_ms"] = Ms(t0, t5);
  Progress(o, "wrote " + o.out + " (" + std::to_string(o.width) + "x" + std::to_string(o.height) + ", " +
                  std::to_string(masks.valid_count) + " valid pixels, " + std::to_string(Ms(t0, t5)) + " ms)");
  return {{"out", o.out},
          {"size", {o.width, o.height}},
          {"cameras", static_cast<int>(cams.cameras.size())},
          {"valid_pixels", masks.valid_count},
          {"exposure_scale", cams.exposure_scale},
          {"sun", sun.summary},
          {"time_place", {{"time", plan.time_place.time_iso8601.empty() ? nlohmann::json() : nlohmann::json(plan.time_place.time_iso8601)},
                          {"latitude_deg", plan.time_place.latitude_deg ? nlohmann::json(*plan.time_place.latitude_deg) : nlohmann::json()},
                          {"longitude_deg", plan.time_place.longitude_deg ? nlohmann::json(*plan.time_place.longitude_deg) : nlohmann::json()},
                          {"source", plan.time_place.source},
                          {"why_no_time", plan.time_place.why_no_time}}},
          {"merge", cams.merge_report},
          {"color_correction", colour.summary},
          {"lens_profile", cams.lens_profile},
          {"stars", unwrapped.stars ? unwrapped.stars->ToJson() : nlohmann::json()},
          {"stages", stages},
          {"skipped", skipped},
          {"sources", cams.sources}};
}

}  // namespace skycal::capture
