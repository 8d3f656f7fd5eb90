#include "capture_verb.h"

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

#include "chart_verb.h"
#include "command_line.h"
#include "option_values.h"
#include "render_verb.h"
#include "stars_verb.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/rig.h"
#include "skycal/capture/solar_position.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/render/renderer.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

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
  if (lens.model == capture::LensModel::kLatLong) return {0.0, 0.0, 0.0};
  return {0.0, 90.0, 0.0};
}

bool CaptureOptions::IsValid(std::string* why) const {
  if (brackets.empty() == rig_path.empty()) {
    *why = "give either --brackets IMG... (one camera) or --rig RIG.json";
    return false;
  }
  // Lens flags that contradict the input: refused, never silently dropped.
  std::vector<std::string> lens_flags;
  if (lens_fov_given) lens_flags.push_back("--lens-fov-deg");
  if (lens_center_given) lens_flags.push_back("--lens-center");
  if (lens_radius_given) lens_flags.push_back("--lens-radius");
  if (kb_given) lens_flags.push_back("--kb-k");
  if (vignetting_given) lens_flags.push_back("--vignetting");
  auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& f : v) s += (s.empty() ? "" : ", ") + f;
    return s;
  };
  if (!rig_path.empty() && (lens_model_given || !lens_flags.empty() || camera_ypr_deg)) {
    *why = "--rig: the rig file gives each camera's lens and rotation; drop --lens, --camera-rotation and the "
           "other lens flags";
    return false;
  }
  if (lens.model == capture::LensModel::kLatLong && !lens_flags.empty()) {
    *why = "--lens latlong: " + joined(lens_flags) +
           " describe a fisheye's image circle; a lat-long input has none (it spans 360 x 180 degrees, its "
           "centre and radius follow from its size). Drop them, or give the fisheye model with --lens";
    return false;
  }
  if (kb_given && lens.model != capture::LensModel::kKannalaBrandt) {
    *why = std::string("--kb-k: Kannala-Brandt coefficients need --lens kannala-brandt (got --lens ") +
           capture::LensModelName(lens.model) + ")";
    return false;
  }
  if (!brackets.empty() && brackets.size() < 2) {
    *why = "--brackets: at least two exposures are needed to merge (got 1)";
    return false;
  }
  if (!exposure_times_s.empty() && exposure_times_s.size() != brackets.size()) {
    *why = "--exposure-times: " + std::to_string(exposure_times_s.size()) + " times for " +
           std::to_string(brackets.size()) + " brackets";
    return false;
  }
  if (width < 16 || height < 8 || width > 16384 || width != 2 * height) {
    *why = "--size: expected a 2:1 lat-long between 16x8 and 16384x8192";
    return false;
  }
  if (out.size() < 5 || out.substr(out.size() - 4) != ".exr") {
    *why = "--out: expected a path ending in .exr";
    return false;
  }
  const bool any_place = !time_iso.empty() || latitude_deg || longitude_deg;
  const bool all_place = !time_iso.empty() && latitude_deg && longitude_deg;
  if (any_place && !all_place) {
    *why = "--time, --lat and --lon go together (the sun by NREL SPA needs all three)";
    return false;
  }
  if (!(std::abs(north_longitude_deg) <= 360.0)) {
    *why = "--north-longitude: expected degrees in [-360, 360]";
    return false;
  }
  if (!chart_path.empty() && !color_correction_path.empty()) {
    *why = "--chart and --color-correction: give one (--chart fits the correction from a chart image now, "
           "--color-correction reads one skycal chart wrote)";
    return false;
  }
  if (chart_corners && chart_path.empty()) {
    *why = "--chart-corners: needs --chart IMG (the image the corners are in)";
    return false;
  }
  if ((!chart_path.empty() || !color_correction_path.empty()) && input_colorspace != "lin_rec709") {
    *why = std::string(chart_path.empty() ? "--color-correction" : "--chart") +
           " with --input-colorspace " + input_colorspace +
           ": the chart's 3x3 already takes camera RGB to lin_rec709; drop one of them";
    return false;
  }
  if (!remove_stars && !(stars == capture::StarRemovalOptions{})) {
    *why = "--star-window, --star-sigma, --star-contrast, --star-max-pixels: only with --remove-stars "
           "(without it no star is removed and they would do nothing)";
    return false;
  }
  if (remove_stars && !stars.IsValid(why)) return false;
  return merge.IsValid(why);
}

namespace {
// The chart correction of this capture, or nothing: read (--color-correction) or fitted from
// the chart image through the merge's response curve (--chart).
std::optional<capture::ColorCorrection> CaptureColorCorrection(const CaptureOptions& o,
                                                               const std::vector<float>& response_curve) {
  if (!o.color_correction_path.empty()) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(ReadFile(o.color_correction_path));
    } catch (const nlohmann::json::exception& e) {
      throw Error(o.color_correction_path + ": --color-correction: not valid JSON (" + e.what() + ")");
    }
    return capture::ColorCorrectionFromJson(j, o.color_correction_path);
  }
  if (o.chart_path.empty()) return std::nullopt;
  capture::ChartOptions chart;
  chart.corners = o.chart_corners;
  return capture::CorrectionFromChartImage(o.chart_path, response_curve, chart, o.chart_label);
}
}  // namespace

nlohmann::json RunCaptureImpl(const CaptureOptions& o) {
  // Progress lines on stderr unless o.verbose is off (the bench runs the verb many times).
  const auto progress = [&o](const std::string& line) {
    if (o.verbose) Log("capture", line);
  };
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  // Inputs first (the rig names its cameras' images): --out must replace none of them.
  std::vector<NamedPath> inputs;
  for (const auto& p : o.brackets) inputs.push_back({"--brackets", p});
  if (!o.chart_path.empty()) inputs.push_back({"--chart", o.chart_path});
  if (!o.color_correction_path.empty()) inputs.push_back({"--color-correction", o.color_correction_path});
  std::vector<capture::RigCamera> rig_cameras;
  if (!o.rig_path.empty()) {
    inputs.push_back({"--rig", o.rig_path});
    rig_cameras = capture::ReadRigFile(o.rig_path);
    for (const auto& cam : rig_cameras) inputs.push_back({"--rig " + o.rig_path + " camera '" + cam.name + "' image", cam.image});
  }
  RefuseOutputsOverInputs({{"--out", o.out}}, inputs);
  { AtomicOutput probe(o.out); }  // fail early on an unwritable destination
  // The sun by SPA first: a bad time or place is refused before any heavy work.
  std::optional<capture::SpaResult> spa;
  capture::SpaInput spa_input;
  if (!o.time_iso.empty()) {
    spa_input = capture::ParseIso8601(o.time_iso, "--time");
    spa_input.latitude_deg = *o.latitude_deg;
    spa_input.longitude_deg = *o.longitude_deg;
    spa = capture::ComputeSolarPosition(spa_input);
  }
  nlohmann::json stages = nlohmann::json::object();
  nlohmann::json skipped = nlohmann::json::array();
  nlohmann::json sources = nlohmann::json::array();
  const auto t0 = Clock::now();

  // 1. Merge (single camera) or load the rig's HDR images.
  std::vector<capture::RigCamera> cameras;
  std::vector<ImageRGB> images, measured;
  double exposure_scale = 1.0;
  nlohmann::json merge_report;
  std::vector<float> response_curve;  // the merge's, for a chart image of the same camera
  if (!o.brackets.empty()) {
    nlohmann::json load_report;
    const auto brackets = capture::LoadBrackets(o.brackets, o.exposure_times_s, 0, &load_report);
    capture::MergeResult merged = capture::MergeBrackets(brackets, o.merge);
    exposure_scale = merged.exposure_scale;
    merge_report = merged.report;
    response_curve = merged.response_curve;
    capture::RigCamera cam;
    cam.lens = o.lens;
    cam.width = merged.radiance.width;
    cam.height = merged.radiance.height;
    if (!o.lens_center_given) {
      cam.lens.center_x = 0.5 * (cam.width - 1);
      cam.lens.center_y = 0.5 * (cam.height - 1);
    }
    if (!o.lens_radius_given) cam.lens.radius_px = 0.5 * std::min(cam.width, cam.height);
    if (cam.lens.model == capture::LensModel::kLatLong) cam.lens = capture::LatLongLens(cam.width, cam.height);
    if (!cam.lens.IsValid(&why, cam.width, cam.height)) throw Error("lens: " + why);
    const std::array<double, 3> ypr = o.CameraRotationDeg();
    cam.rotation = capture::RotationFromYawPitchRollDeg(ypr[0], ypr[1], ypr[2]);
    if (cam.lens.model == capture::LensModel::kLatLong && !o.camera_ypr_deg)
      progress("--lens latlong: camera rotation = identity (the input is already a world lat-long)");
    cam.name = "camera";
    measured.push_back(PlaneAsImage(merged.well_measured, cam.width, cam.height));
    images.push_back(std::move(merged.radiance));
    cameras.push_back(cam);
    for (const auto& p : o.brackets) sources.push_back({{"path", p}, {"sha256", Sha256OfFile(p)}});
    progress("merged " + std::to_string(brackets.size()) + " brackets (" + std::to_string(merged.not_well_measured) +
                       " pixels no exposure measured well)");
  } else {
    cameras = rig_cameras;
    for (const auto& cam : cameras) {
      ExrRGB exr = ReadExrRGB(cam.image);
      measured.push_back(PlaneAsImage(std::vector<float>(static_cast<size_t>(exr.image.width) * exr.image.height, 1.0f),
                                      exr.image.width, exr.image.height));
      images.push_back(std::move(exr.image));
      sources.push_back({{"path", cam.image}, {"sha256", Sha256OfFile(cam.image)}});
    }
    skipped.push_back({{"stage", "merge"}, {"reason", "--rig: the cameras' images are HDR already"}});
  }
  const auto t1 = Clock::now();
  stages["merge_ms"] = Ms(t0, t1);

  // 2. Colour: camera space -> the working space (scene-linear Rec.709): the chart's 3x3, or OCIO.
  nlohmann::json color_summary;
  const std::optional<capture::ColorCorrection> chart = CaptureColorCorrection(o, response_curve);
  if (chart) {
    for (ImageRGB& img : images) capture::ApplyColorCorrection(chart->matrix, &img);
    color_summary = ChartSummary(*chart);
    Log("capture", "colour chart correction (" + (o.chart_path.empty() ? o.color_correction_path : o.chart_path) +
                       ") applied: chart mean CIEDE2000 " +
                       std::to_string(color_summary["delta_e2000_before"]["mean"].get<double>()) + " -> " +
                       std::to_string(color_summary["delta_e2000_after"]["mean"].get<double>()));
  } else if (o.input_colorspace != "lin_rec709") {
    for (ImageRGB& img : images) color::ConvertColorspace(img, o.input_colorspace, "lin_rec709");
  } else {
    skipped.push_back({{"stage", "colour"}, {"reason", "input already lin_rec709"}});
  }
  const auto t2 = Clock::now();
  stages["colour_ms"] = Ms(t1, t2);

  // 3. Unwrap / stitch.
  std::vector<std::pair<capture::RigCamera, const ImageRGB*>> views, measured_views;
  for (size_t i = 0; i < cameras.size(); ++i) {
    views.push_back({cameras[i], &images[i]});
    measured_views.push_back({cameras[i], &measured[i]});
  }
  std::vector<float> coverage;
  ImageRGB frame = capture::UnwrapToLatLong(views, o.width, o.height, &coverage);
  const ImageRGB measured_frame = capture::UnwrapToLatLong(measured_views, o.width, o.height, nullptr);
  std::optional<capture::StarRemovalResult> stars;
  if (o.remove_stars) {
    stars = capture::RemoveStars(frame, o.stars);
    frame = std::move(stars->image);
    Log("capture", "removed " + std::to_string(stars->stars) + " stars (" + std::to_string(stars->pixels_replaced) +
                       " pixels replaced by their neighbourhood's median)");
  }
  const auto t3 = Clock::now();
  stages["unwrap_ms"] = Ms(t2, t3);

  // 4. The sun: SPA and detection; the camera heading from the two when both exist.
  nlohmann::json sun = nlohmann::json::object();
  std::optional<std::array<double, 3>> sun_dir;
  if (spa) {
    sun_dir = capture::SunDirectionInFrame(*spa, o.north_longitude_deg);
    sun["spa"] = {{"zenith_deg", spa->zenith_deg}, {"azimuth_deg", spa->azimuth_deg}};
  }
  std::string detect_why;
  if (auto d = capture::DetectSun(frame, &detect_why)) {
    sun["detected"] = {{"direction", d->direction},
                       {"elevation_deg", latlong::ElevationDeg(d->direction)},
                       {"azimuth_deg", latlong::AzimuthDeg(d->direction)},
                       {"clipped", d->clipped},
                       {"contrast", d->contrast}};
    if (spa) {
      // Heading: how far the rig's longitude 0 is from where north was assumed.
      double offset = latlong::AzimuthDeg(d->direction) - latlong::AzimuthDeg(*sun_dir);
      offset = std::remainder(offset, 360.0);
      sun["camera_heading_offset_deg"] = offset;
      sun["suggested_north_longitude_deg"] = std::remainder(o.north_longitude_deg + offset, 360.0);
      progress("camera heading: the detected sun is " + std::to_string(offset) +
                         " deg of longitude from the SPA sun; --north-longitude " +
                         std::to_string(sun["suggested_north_longitude_deg"].get<double>()) + " aligns them");
    } else {
      sun_dir = d->direction;
    }
  } else {
    sun["detection"] = "no distinct sun: " + detect_why;
  }
  if (!sun_dir) skipped.push_back({{"stage", "sunDirection"}, {"reason", "no --time/--lat/--lon and no sun detected"}});
  const auto t4 = Clock::now();
  stages["sun_ms"] = Ms(t3, t4);

  // 5. Masks and the frame.
  const size_t n = static_cast<size_t>(o.width) * o.height;
  ExrPlane valid{"mask.valid", std::vector<float>(n, 0.0f)}, below{"mask.belowHorizon", std::vector<float>(n, 0.0f)};
  long long valid_count = 0;
  for (int y = 0; y < o.height; ++y) {
    const bool under = latlong::Latitude(y, o.height) <= 0.0;
    for (int x = 0; x < o.width; ++x) {
      const size_t i = static_cast<size_t>(y) * o.width + x;
      const bool ok = coverage[i] > 0.0f && measured_frame.pixels[3 * i] > 0.5f;
      valid.values[i] = ok ? 1.0f : 0.0f;
      below.values[i] = under ? 1.0f : 0.0f;
      valid_count += ok;
    }
  }
  // Cloud probability: colour against the clear-sky model at this sun (bundled preset).
  std::vector<ExrPlane> planes = {valid, below};
  if (stars) planes.push_back({"mask.stars", std::vector<float>(stars->mask.begin(), stars->mask.end())});
  if (sun_dir) {
    render::RenderRequest req;
    req.sun_dir = *sun_dir;
    req.width = o.width;
    req.height = o.height;
    req.sun_disc = false;
    const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(DefaultPresetPath()), req);
    const capture::CloudMask cm = capture::EstimateCloudProbability(frame, clear, sun_dir, {});
    planes.push_back({"mask.cloud", cm.probability});
    sun["cloud_offset_ln_rb"] = cm.clear_offset;
    stages["cloudy_pixels"] = cm.cloudy_pixels;
  } else {
    skipped.push_back({{"stage", "cloud mask"}, {"reason", "needs the sun direction for the clear-sky expectation"}});
  }
  const auto t_mask = Clock::now();
  stages["mask_ms"] = Ms(t4, t_mask);
  ExrAttributes attrs;
  attrs.envmap_latlong = true;
  if (sun_dir) {
    attrs.v3fs["sunDirection"] = {static_cast<float>((*sun_dir)[0]), static_cast<float>((*sun_dir)[1]),
                                  static_cast<float>((*sun_dir)[2])};
  }
  if (spa) {
    attrs.strings["skycalCaptureTime"] = o.time_iso;
    attrs.floats["skycalLatitudeDeg"] = static_cast<float>(*o.latitude_deg);
    attrs.floats["skycalLongitudeDeg"] = static_cast<float>(*o.longitude_deg);
    const double local_h = spa_input.hour + spa_input.minute / 60.0 + spa_input.second / 3600.0;
    attrs.floats["skycalTimeOfDay"] = static_cast<float>(local_h);
  }
  attrs.floats["skycalExposureScale"] = static_cast<float>(exposure_scale);
  attrs.strings["skycalSources"] = sources.dump();
  attrs.strings["skycalLens"] = o.rig_path.empty() ? std::string(capture::LensModelName(o.lens.model)) : "rig " + o.rig_path;
  if (o.rig_path.empty()) {
    const std::array<double, 3> ypr = o.CameraRotationDeg();
    attrs.v3fs["skycalCameraRotationDeg"] = {static_cast<float>(ypr[0]), static_cast<float>(ypr[1]), static_cast<float>(ypr[2])};
  }
  if (chart) attrs.strings["skycalColorCorrection"] = capture::ColorCorrectionToJson(*chart).dump();
  attrs.strings["skycalUnits"] = "relative radiance: linear / (t ISO/100 / N^2), scene-linear Rec.709";
  attrs.strings["skycalVersion"] = kSkycalVersion;
  WriteExrRGBWithPlanes(o.out, frame, planes, attrs);
  const auto t5 = Clock::now();
  stages["write_ms"] = Ms(t_mask, t5);
  stages["total_ms"] = Ms(t0, t5);
  progress("wrote " + o.out + " (" + std::to_string(o.width) + "x" + std::to_string(o.height) + ", " +
                     std::to_string(valid_count) + " valid pixels, " + std::to_string(Ms(t0, t5)) + " ms)");
  return {{"out", o.out},
          {"size", {o.width, o.height}},
          {"cameras", static_cast<int>(cameras.size())},
          {"valid_pixels", valid_count},
          {"exposure_scale", exposure_scale},
          {"sun", sun},
          {"merge", merge_report},
          {"color_correction", color_summary},
          {"stars", stars ? stars->ToJson() : nlohmann::json()},
          {"stages", stages},
          {"skipped", skipped},
          {"sources", sources}};
}

CaptureOptions ParseCaptureArgs(int argc, char** argv) {
  VerbCommandLine cl(
      "capture", "skycal capture: exposure brackets to a calibrated lat-long reference frame",
      "  skycal capture --brackets IMG... [--exposure-times T1,T2,...] [--response auto|debevec|weighted|robertson|linear|srgb]\n"
      "                 [--lens latlong|equidistant|equisolid|stereographic|kannala-brandt] [--lens-fov-deg F]\n"
      "                 [--lens-center X,Y] [--lens-radius R] [--kb-k K1,K2,K3,K4] [--vignetting A,B,C]\n"
      "                 [--camera-rotation YAW,PITCH,ROLL] | --rig RIG.json\n"
      "                 [--input-colorspace NAME | --color-correction CORRECTION.json | --chart IMG [--chart-corners ...]]\n"
      "                 [--remove-stars [--star-window PX] [--star-sigma K] [--star-contrast C] [--star-max-pixels N]]\n"
      "                 [--time ISO8601 --lat DEG --lon DEG [--north-longitude DEG]]\n"
      "                 [--size WxH] --out FRAME.exr [--json]",
      "Stage timings (merge, colour, unwrap, sun, write) are in the JSON summary.");
  CaptureOptions o;
  std::optional<std::string> exposure_times, response, lens, lens_center, kb_k, vignetting, rotation, size, chart_corners;
  std::optional<double> lens_fov, lens_radius;
  bool json = false;
  cl.List("--brackets", &o.brackets, "IMG",
          "8/16-bit images of one camera, one per exposure (repeat the flag or list them)");
  cl.Text("--exposure-times", &exposure_times, "T,...",
          "seconds, one per bracket (default: EXIF ExposureTime; FNumber and ISO from\n"
          "EXIF put frames of a time-lapse on one scale)");
  cl.Text("--response", &response, "NAME",
          "camera response: auto (default: weighted's per-channel curves, or debevec's when\n"
          "the channels' curves have one shape; README \"Capture: lat-long brackets and\n"
          "camera-response recovery\"), debevec, weighted, robertson (recovered), linear, srgb");
  cl.Text("--lens", &lens, "NAME",
          "lens model of the single camera: latlong, equidistant, equisolid (default),\n"
          "stereographic or kannala-brandt");
  cl.Number("--lens-fov-deg", &lens_fov, "F", "lens field of view in degrees (default 180)");
  cl.Text("--lens-center", &lens_center, "X,Y", "lens centre in pixels (default: the image centre)");
  cl.Number("--lens-radius", &lens_radius, "R", "lens image-circle radius in pixels (default: half the shorter side)");
  cl.Text("--kb-k", &kb_k, "K1,K2,K3,K4", "Kannala-Brandt coefficients (--lens kannala-brandt)");
  cl.Text("--vignetting", &vignetting, "A,B,C", "vignetting gain 1 + a r^2 + b r^4 + c r^6, r = radius / lens radius");
  cl.Text("--camera-rotation", &rotation, "Y,P,R",
          "the camera's optical axis: azimuth (lat-long longitude) and elevation, and roll,\n"
          "degrees (default 0,90,0: looking straight up; with --lens latlong 0,0,0: the\n"
          "panorama is already the world's lat-long)");
  cl.Text("--rig", &o.rig_path, "RIG.json",
          "several cameras (format: capture/include/skycal/capture/rig.h; each camera's\n"
          "image is an HDR EXR, e.g. merged by an earlier capture of that camera with\n"
          "--lens latlong... or any linear EXR); replaces --brackets and the lens flags");
  cl.Text("--input-colorspace", &o.input_colorspace, "CS",
          "OCIO colour space of the camera data (default lin_rec709; $OCIO or\n"
          "config/skycal.ocio), converted to lin_rec709");
  cl.Text("--color-correction", &o.color_correction_path, "CORRECTION.json",
          "a colour-chart correction from skycal chart (camera RGB -> lin_rec709), applied\n"
          "to the merged image and stored in the frame (skycalColorCorrection)");
  cl.Text("--chart", &o.chart_path, "IMG",
          "fit the colour-chart correction now from this image of a ColorChecker Classic\n"
          "through the same camera (a bracket: linearised by this merge's response; or\n"
          "an EXR), then apply and store it as --color-correction does");
  cl.Text("--chart-corners", &chart_corners, "X1,Y1,...",
          "--chart's corners in pixels (patch 1 first, clockwise); default: detected (OpenCV mcc)");
  cl.Text("--chart-label", &o.chart_label, "TEXT", "which exposure set --chart belongs to, e.g. nd (stored)");
  cl.Flag("--remove-stars", &o.remove_stars,
          "night frames: remove the stars from the lat-long (as skycal stars; mask.stars\n"
          "channel: 1 where replaced)");
  RegisterStarOptions(cl, &o.stars);
  cl.Text("--time", &o.time_iso, "ISO8601", "capture time with its UTC offset; with --lat and --lon: the sun by NREL SPA");
  cl.Number("--lat", &o.latitude_deg, "DEG", "capture latitude, degrees, north positive");
  cl.Number("--lon", &o.longitude_deg, "DEG", "capture longitude, degrees, east positive");
  cl.Number("--north-longitude", &o.north_longitude_deg, "DEG", "lat-long longitude that points to geographic north (default 0)");
  cl.Text("--size", &size, "WxH", "output lat-long in pixels (default 2048x1024)");
  cl.Text("--out", &o.out, "FRAME.exr",
          "reference frame (required): R, G, B radiance + mask.valid, mask.belowHorizon and (with a\n"
          "sun) mask.cloud (probability) channels,\n"
          "sunDirection, time, place, exposure scale, sources, lens");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (chart_corners) o.chart_corners = ParseChartCorners(*chart_corners, "--chart-corners");
  if (exposure_times) o.exposure_times_s = ParseNumberList(*exposure_times, "--exposure-times");
  if (response) o.merge.response = capture::ParseResponseModel(*response, "--response");
  if (lens) {
    auto m = capture::LensModelFromName(*lens);
    if (!m) throw Error("--lens: unknown model '" + *lens + "' (expected latlong, equidistant, equisolid, stereographic or kannala-brandt)");
    o.lens.model = *m;
    o.lens_model_given = true;
  }
  if (lens_fov) {
    o.lens.fov_deg = *lens_fov;
    o.lens_fov_given = true;
  }
  if (lens_center) {
    const auto v = ParseNumberList(*lens_center, "--lens-center");
    if (v.size() != 2) throw Error("--lens-center: expected X,Y in pixels");
    o.lens.center_x = v[0];
    o.lens.center_y = v[1];
    o.lens_center_given = true;
  }
  if (lens_radius) {
    o.lens.radius_px = *lens_radius;
    o.lens_radius_given = true;
  }
  if (kb_k) {
    const auto v = ParseNumberList(*kb_k, "--kb-k");
    if (v.size() != 4) throw Error("--kb-k: expected K1,K2,K3,K4");
    for (int i = 0; i < 4; ++i) o.lens.kb_k[i] = v[i];
    o.kb_given = true;
  }
  if (vignetting) {
    const auto v = ParseNumberList(*vignetting, "--vignetting");
    if (v.size() != 3) throw Error("--vignetting: expected A,B,C");
    for (int i = 0; i < 3; ++i) o.lens.vignetting[i] = v[i];
    o.vignetting_given = true;
  }
  if (rotation) {
    const auto v = ParseNumberList(*rotation, "--camera-rotation");
    if (v.size() != 3) throw Error("--camera-rotation: expected YAW,PITCH,ROLL in degrees");
    o.camera_ypr_deg = std::array<double, 3>{v[0], v[1], v[2]};
  }
  if (size) {
    const auto wh = ParseSize(*size, "--size");
    o.width = wh[0];
    o.height = wh[1];
  }
  return o;
}

int RunCapture(int argc, char** argv) {
  return RunVerb("capture", WantsJson(argc, argv), [&]() { return RunCaptureImpl(ParseCaptureArgs(argc, argv)); });
}

}  // namespace skycal::cli
