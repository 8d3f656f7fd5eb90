#include "capture_verb.h"

#include <optional>
#include <string>

#include "chart_verb.h"
#include "command_line.h"
#include "option_values.h"
#include "stars_verb.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {

namespace {

// The capture library's messages name CaptureOptions' fields; the user set them with these flags.
std::string WithCaptureFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {
      {"CaptureOptions::brackets", "--brackets"},
      {"CaptureOptions::exposure_times_s", "--exposure-times"},
      {"CaptureOptions::rig_path", "--rig"},
      {"CaptureOptions::lens_model_given", "--lens"},
      {"CaptureOptions::lens.model", "--lens"},
      {"CaptureOptions::lens_fov_given", "--lens-fov-deg"},
      {"CaptureOptions::lens_center_given", "--lens-center"},
      {"CaptureOptions::lens_radius_given", "--lens-radius"},
      {"CaptureOptions::kb_given", "--kb-k"},
      {"CaptureOptions::vignetting_given", "--vignetting"},
      {"CaptureOptions::lens_profile", "--lens-profile"},
      {"CaptureOptions::camera_ypr_deg", "--camera-rotation"},
      {"CaptureOptions::input_colorspace", "--input-colorspace"},
      {"CaptureOptions::color_correction_path", "--color-correction"},
      {"CaptureOptions::chart_path", "--chart"},
      {"CaptureOptions::chart_corners", "--chart-corners"},
      {"CaptureOptions::remove_stars", "--remove-stars"},
      {"CaptureOptions::stars", "--star-window, --star-sigma, --star-contrast, --star-max-pixels"},
      {"CaptureOptions::time_iso", "--time"},
      {"CaptureOptions::latitude_deg", "--lat"},
      {"CaptureOptions::longitude_deg", "--lon"},
      {"CaptureOptions::north_longitude_deg", "--north-longitude"},
      {"CaptureOptions::width x height", "--size"},
      {"CaptureOptions::out", "--out"}};
  return WithStarFlags(FieldsAsFlags(message, kFlags));
}

}  // namespace

nlohmann::json RunCaptureImpl(const CaptureOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(WithCaptureFlags(why));
  try {
    return capture::RunCapturePipeline(o);
  } catch (const Error& e) {
    throw Error(WithCaptureFlags(e.what()));
  }
}

namespace {
// The single camera's lens flags, as typed; ApplyLensArgs checks and converts them.
struct LensArgs {
  std::optional<std::string> lens, center, kb_k, vignetting, rotation;
  std::optional<double> fov, radius;
};

void ApplyLensArgs(const LensArgs& a, CaptureOptions* o) {
  if (a.lens) {
    auto m = capture::LensModelFromName(*a.lens);
    if (!m) throw Error("--lens: unknown model '" + *a.lens + "' (expected latlong, equidistant, equisolid, stereographic or kannala-brandt)");
    o->lens.model = *m;
    o->lens_model_given = true;
  }
  if (a.fov) {
    o->lens.fov_deg = *a.fov;
    o->lens_fov_given = true;
  }
  if (a.center) {
    const auto v = ParseNumberList(*a.center, "--lens-center");
    if (v.size() != 2) throw Error("--lens-center: expected X,Y in pixels");
    o->lens.center_x = v[0];
    o->lens.center_y = v[1];
    o->lens_center_given = true;
  }
  if (a.radius) {
    o->lens.radius_px = *a.radius;
    o->lens_radius_given = true;
  }
  if (a.kb_k) {
    const auto v = ParseNumberList(*a.kb_k, "--kb-k");
    if (v.size() != 4) throw Error("--kb-k: expected K1,K2,K3,K4");
    for (int i = 0; i < 4; ++i) o->lens.kb_k[i] = v[i];
    o->kb_given = true;
  }
  if (a.vignetting) {
    const auto v = ParseNumberList(*a.vignetting, "--vignetting");
    if (v.size() != 3) throw Error("--vignetting: expected A,B,C");
    for (int i = 0; i < 3; ++i) o->lens.vignetting[i] = v[i];
    o->vignetting_given = true;
  }
  if (a.rotation) {
    const auto v = ParseNumberList(*a.rotation, "--camera-rotation");
    if (v.size() != 3) throw Error("--camera-rotation: expected YAW,PITCH,ROLL in degrees");
    o->camera_ypr_deg = std::array<double, 3>{v[0], v[1], v[2]};
  }
}
}  // namespace

// The single camera's lens flags (LensArgs, applied by ApplyLensArgs) and its lens profile.
void RegisterLensArgs(VerbCommandLine& cl, LensArgs* l, CaptureOptions* opts) {
  LensArgs& la = *l;
  CaptureOptions& o = *opts;
  cl.Text("--lens", &la.lens, "NAME",
          "lens model of the single camera: latlong, equidistant, equisolid (default),\n"
          "stereographic or kannala-brandt");
  cl.Number("--lens-fov-deg", &la.fov, "F", "lens field of view in degrees (default 180)");
  cl.Text("--lens-center", &la.center, "X,Y", "lens centre in pixels (default: the image centre)");
  cl.Number("--lens-radius", &la.radius, "R", "lens image-circle radius in pixels (default: half the shorter side)");
  cl.Text("--kb-k", &la.kb_k, "K1,K2,K3,K4", "Kannala-Brandt coefficients (--lens kannala-brandt)");
  cl.Text("--vignetting", &la.vignetting, "A,B,C", "vignetting gain 1 + a r^2 + b r^4 + c r^6, r = radius / lens radius");
  cl.Text("--lens-profile", &o.lens_profile, "SPEC",
          "lensfun lens profile (docs/capture.md): default, looked up from the first bracket's\n"
          "EXIF (Make, Model, LensModel, FocalLength, FNumber; no match: said, and on without);\n"
          "none: off; LENS_MAKER:LENS_MODEL[@CAMERA_MAKER:CAMERA_MODEL] as lensfun names them\n"
          "(no match: an error naming the closest). Corrects vignetting, TCA and distortion and\n"
          "gives the projection and image circle; --lens, --lens-center, --lens-radius,\n"
          "--lens-fov-deg, --kb-k and --vignetting override it");
  cl.Text("--camera-rotation", &la.rotation, "Y,P,R",
          "the camera's optical axis: azimuth (lat-long longitude) and elevation, and roll,\n"
          "degrees (default 0,90,0: looking straight up; with --lens latlong 0,0,0: the\n"
          "panorama is already the world's lat-long)");
}

CaptureOptions ParseCaptureArgs(int argc, char** argv) {
  VerbCommandLine cl(
      "capture", "skycal capture: exposure brackets to a calibrated lat-long reference frame",
      "  skycal capture --brackets IMG... [--exposure-times T1,T2,...] [--response auto|debevec|weighted|robertson|linear|srgb]\n"
      "                 [--no-response-prior]\n"
      "                 [--lens latlong|equidistant|equisolid|stereographic|kannala-brandt] [--lens-fov-deg F]\n"
      "                 [--lens-center X,Y] [--lens-radius R] [--kb-k K1,K2,K3,K4] [--vignetting A,B,C]\n"
      "                 [--camera-rotation YAW,PITCH,ROLL] [--lens-profile none|LENS_MAKER:LENS_MODEL[@CAMERA_MAKER:CAMERA_MODEL]]\n"
      "                 | --rig RIG.json\n"
      "                 [--input-colorspace NAME | --color-correction CORRECTION.json | --chart IMG [--chart-corners ...]]\n"
      "                 [--remove-stars [--star-window PX] [--star-sigma K] [--star-contrast C] [--star-max-pixels N]]\n"
      "                 [--time ISO8601 --lat DEG --lon DEG [--north-longitude DEG]]\n"
      "                 [--size WxH] --out FRAME.exr [--json]",
      "Stage timings (merge, colour, unwrap, sun, write) are in the JSON summary.");
  CaptureOptions o;
  std::optional<std::string> exposure_times, response, size, chart_corners;
  LensArgs la;
  bool json = false;
  cl.List("--brackets", &o.brackets, "IMG",
          "8/16-bit images of one camera, one per exposure (repeat the flag or list them);\n"
          "or camera RAW files (.dng .cr2 .nef .arw ...: decoded linear by LibRaw, no response\n"
          "recovery, exposure from the file; docs/capture.md)");
  cl.Text("--exposure-times", &exposure_times, "T,...",
          "seconds, one per bracket (default: EXIF ExposureTime; FNumber and ISO from\n"
          "EXIF put frames of a time-lapse on one scale)");
  cl.Text("--response", &response, "NAME",
          "camera response: auto (default: weighted's per-channel curves, or debevec's when\n"
          "the channels' curves have one shape; docs/capture.md), debevec, weighted, robertson (recovered), linear, srgb");
  bool no_prior = false;
  cl.Flag("--no-response-prior", &no_prior,
          "debevec / auto: leave what brackets a constant step apart cannot determine to the\n"
          "smoothness term instead of the EMoR camera-curve prior (docs/capture.md)");
  RegisterLensArgs(cl, &la, &o);
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
  o.merge.emor_prior = !no_prior;
  ApplyLensArgs(la, &o);
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
