#include "probe_extract_verb.h"

#include <cmath>
#include <iostream>

#include "args.h"
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

constexpr const char* kHelp = R"(skycal probe-extract: measure the gray diffuse ball in a linear photograph

  skycal probe-extract --image IMG.exr [--circle CX,CY,R] [--camera-rotation YAW,PITCH,ROLL]
                       [--albedo A] [--clip-level V] --out SAMPLES.json [--json]

  --image IMG.exr          linear EXR (scene-referred, same units as the reference skies)
  --circle CX,CY,R         the ball's centre and radius in pixels (pixel centres at integer
                           coordinates); default: detected (Hough circle + edge refinement)
  --camera-rotation Y,P,R  the camera's yaw (azimuth), pitch (elevation), roll in degrees
                           (capture/rig.h convention; default 0,0,0: looking along +Z, level)
  --albedo A               the ball's Lambertian albedo in (0, 1] (default 0.18)
  --clip-level V           pixels with any channel >= V are saturated and rejected (default: none)
  --out SAMPLES.json       samples file for `skycal fit --probe STEM=SAMPLES.json` (atomic)
  --json                   print the summary on stdout (the log goes to stderr)
The ball is modelled orthographically (capture/probe.h); samples are bins of about equal
solid angle with their world normal (+Y up), mean radiance and pixel count. Exit 1 and
nothing written when the ball lies outside the image, is fully clipped or is not found.
)";

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

int RunProbeExtract(int argc, char** argv) {
  if (WantsHelp(argc, argv)) {
    std::cout << kHelp;
    return 0;
  }
  return RunVerb("probe-extract", WantsJson(argc, argv), [&]() {
    Args a(argc, argv, {"image", "circle", "camera-rotation", "albedo", "clip-level", "out"}, {"json"});
    ProbeExtractOptions o;
    o.image = a.Value("image").value_or("");
    o.out = a.Value("out").value_or("");
    if (auto c = a.Vec3("circle")) o.circle = capture::BallCircle{(*c)[0], (*c)[1], (*c)[2]};
    if (auto r = a.Vec3("camera-rotation")) o.camera_ypr_deg = *r;
    if (auto v = a.Number("albedo")) o.albedo = *v;
    if (auto v = a.Number("clip-level")) o.clip_level = *v;
    return RunProbeExtractImpl(o);
  });
}

}  // namespace skycal::cli
