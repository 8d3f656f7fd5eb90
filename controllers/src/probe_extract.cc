#include "probe_extract_verb.h"

#include <cmath>
#include <iostream>

#include "command_line.h"
#include "finite_output.h"
#include "option_values.h"
#include "skycal/capture/rig.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/sha256.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

}  // namespace

bool ProbeExtractOptions::IsValid(std::string* why) const {
  if (image.empty()) {
    *why = "--image IMG.exr is required";
    return false;
  }
  if (out.empty()) {
    *why = "--out SAMPLES.json is required";
    return false;
  }
  if (circle && !(circle->radius_px > 0.0)) {
    *why = "--circle: the radius must be positive";
    return false;
  }
  if (!(albedo > 0.0 && albedo <= 1.0)) {
    *why = "--albedo " + FormatNumber(albedo) + ": expected a value in (0, 1]";
    return false;
  }
  if (!(clip_level > 0.0)) {
    *why = "--clip-level: expected a positive value";
    return false;
  }
  for (double v : camera_ypr_deg) {
    if (!std::isfinite(v) || std::abs(v) > 360.0) {
      *why = "--camera-rotation: expected degrees in [-360, 360]";
      return false;
    }
  }
  return true;
}

nlohmann::json RunProbeExtractImpl(const ProbeExtractOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RefuseOutputsOverInputs({{"--out", o.out}}, {{"--image", o.image}});
  { AtomicOutput probe(o.out); }  // fail early on an unwritable destination
  const ExrRGB exr = ReadExrRGB(o.image);
  RequireValidShare(o.image, exr.image);
  const auto rotation = capture::RotationFromYawPitchRollDeg(o.camera_ypr_deg[0], o.camera_ypr_deg[1], o.camera_ypr_deg[2]);
  capture::ProbeOptions po;
  po.clip_level = o.clip_level;
  capture::ProbeMeasurement m;
  try {
    m = capture::MeasureProbe(exr.image, rotation, o.circle, po);
  } catch (const Error& e) {
    throw Error(o.image + ": " + e.what());
  }
  nlohmann::json samples = nlohmann::json::array();
  for (const auto& s : m.samples) samples.push_back({{"normal", s.normal}, {"radiance", s.radiance}, {"pixels", s.pixels}});
  nlohmann::json doc = {{"format", "skycal-probe-samples"},
                        {"format_version", 1},
                        {"image", o.image},
                        {"sha256", Sha256OfFile(o.image)},
                        {"circle", {{"cx", m.circle.cx}, {"cy", m.circle.cy}, {"radius_px", m.circle.radius_px}}},
                        {"circle_source", o.circle ? "option" : "detected"},
                        {"camera_rotation",
                         {{"yaw_deg", o.camera_ypr_deg[0]},
                          {"pitch_deg", o.camera_ypr_deg[1]},
                          {"roll_deg", o.camera_ypr_deg[2]},
                          {"camera_to_world", rotation}}},
                        {"albedo", o.albedo},
                        {"clip_level", std::isfinite(o.clip_level) ? nlohmann::json(o.clip_level) : nlohmann::json()},
                        {"max_luminance", m.max_luminance},
                        {"max_luminance_clipped", m.max_luminance_clipped},
                        {"pixels",
                         {{"total", m.pixels_total},
                          {"used", m.pixels_used},
                          {"clipped", m.pixels_clipped},
                          {"nonfinite", m.pixels_nonfinite}}},
                        {"samples", samples}};
  WriteJsonFileAtomically(o.out, doc);
  if (o.verbose)
    Log("probe-extract", o.image + ": ball at (" + std::to_string(m.circle.cx) + ", " + std::to_string(m.circle.cy) +
                           ") r " + std::to_string(m.circle.radius_px) + " px, " + std::to_string(m.samples.size()) +
                           " samples from " + std::to_string(m.pixels_used) + " pixels (" +
                           std::to_string(m.pixels_clipped) + " clipped), max luminance " +
                           std::to_string(m.max_luminance) + (m.max_luminance_clipped ? " (clipped)" : "") +
                           "; wrote " + o.out);
  nlohmann::json summary = doc;
  summary["out"] = o.out;
  return summary;
}

ProbeExtractOptions ParseProbeExtractArgs(int argc, char** argv) {
  VerbCommandLine cl("probe-extract", "skycal probe-extract: measure the gray diffuse ball in a linear photograph",
                     "  skycal probe-extract --image IMG.exr [--circle CX,CY,R] [--camera-rotation YAW,PITCH,ROLL]\n"
                     "                       [--albedo A] [--clip-level V] --out SAMPLES.json [--json]",
                     "The ball is modelled orthographically (capture/probe.h); samples are bins of about equal\n"
                     "solid angle with their world normal (+Y up), mean radiance and pixel count. Exit 1 and\n"
                     "nothing written when the ball lies outside the image, is fully clipped or is not found.");
  ProbeExtractOptions o;
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
