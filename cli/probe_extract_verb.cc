#include "probe_extract_verb.h"

#include <optional>
#include <string>

#include "command_line.h"
#include "option_values.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

// The library names its ProbeExtractOptions fields; the user typed these flags. Whole
// messages first (the required flags, as the verb always worded them), then each field.
constexpr FieldFlag kFlags[] = {
    {"ProbeExtractOptions::image is empty (expected a linear EXR)", "--image IMG.exr is required"},
    {"ProbeExtractOptions::out is empty (expected a samples JSON path)", "--out SAMPLES.json is required"},
    {"ProbeExtractOptions::image", "--image"},
    {"ProbeExtractOptions::circle", "--circle"},
    {"ProbeExtractOptions::camera_ypr_deg", "--camera-rotation"},
    {"ProbeExtractOptions::albedo", "--albedo"},
    {"ProbeExtractOptions::clip_level", "--clip-level"},
    {"ProbeExtractOptions::out", "--out"}};

}  // namespace

nlohmann::json RunProbeExtractImpl(const controllers::ProbeExtractOptions& o) {
  try {
    return controllers::ExtractProbe(o);
  } catch (const Error& e) {
    throw Error(FieldsAsFlags(e.what(), kFlags));
  }
}

controllers::ProbeExtractOptions ParseProbeExtractArgs(int argc, char** argv) {
  VerbCommandLine cl("probe-extract", "skycal probe-extract: measure the gray diffuse ball in a linear photograph",
                     "  skycal probe-extract --image IMG.exr [--circle CX,CY,R] [--camera-rotation YAW,PITCH,ROLL]\n"
                     "                       [--albedo A] [--clip-level V] --out SAMPLES.json [--json]",
                     "The ball is modelled orthographically (capture/probe.h); samples are bins of about equal\n"
                     "solid angle with their world normal (+Y up), mean radiance and pixel count. Exit 1 and\n"
                     "nothing written when the ball lies outside the image, is fully clipped or is not found.");
  controllers::ProbeExtractOptions o;
  std::optional<std::string> circle, rotation;
  bool json = false;
  cl.Text("--image", &o.image, "IMG.exr", "linear EXR (scene-referred, same units as the reference skies; required)");
  cl.Text("--circle", &circle, "CX,CY,R",
          "the ball's centre and radius in pixels (pixel centres at integer\n"
          "coordinates); default: detected (Hough circle + edge refinement)");
  cl.Text("--camera-rotation", &rotation, "Y,P,R",
          "the camera's yaw (azimuth), pitch (elevation), roll in degrees\n"
          "(capture/rig.h convention; default 0,0,0: looking along +Z, level)");
  cl.Number("--albedo", &o.albedo, "A", "the ball's Lambertian albedo in (0, 1] (default 0.18)");
  cl.Number("--clip-level", &o.clip_level, "V", "pixels with any channel >= V are saturated and rejected (default: none)");
  cl.Text("--out", &o.out, "SAMPLES.json", "samples file for `skycal fit --probe STEM=SAMPLES.json` (atomic; required)");
  cl.Flag("--json", &json, "print the summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (circle) {
    const auto c = ParseVec3(*circle, "--circle");
    o.circle = capture::BallCircle{c[0], c[1], c[2]};
  }
  if (rotation) o.camera_ypr_deg = ParseVec3(*rotation, "--camera-rotation");
  return o;
}

int RunProbeExtract(int argc, char** argv) {
  return RunVerb("probe-extract", WantsJson(argc, argv),
                 [&]() { return RunProbeExtractImpl(ParseProbeExtractArgs(argc, argv)); });
}

}  // namespace skycal::cli
