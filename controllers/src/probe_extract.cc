#include "skycal/controllers/probe_extract.h"

#include <cmath>
#include <iostream>

#include "skycal/capture/rig.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/finite_pixels.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"
#include "skycal/core/sha256.h"

namespace skycal::controllers {
namespace {

// Progress on stderr, prefixed as `skycal probe-extract` always printed it.
void Log(const std::string& message) { std::cerr << "[probe-extract] " << message << std::endl; }

}  // namespace

bool ProbeExtractOptions::IsValid(std::string* why) const {
  if (image.empty()) {
    *why = "ProbeExtractOptions::image is empty (expected a linear EXR)";
    return false;
  }
  if (out.empty()) {
    *why = "ProbeExtractOptions::out is empty (expected a samples JSON path)";
    return false;
  }
  if (circle && !(circle->radius_px > 0.0)) {
    *why = "ProbeExtractOptions::circle: the radius must be positive";
    return false;
  }
  if (!(albedo > 0.0 && albedo <= 1.0)) {
    *why = "ProbeExtractOptions::albedo = " + FormatNumber(albedo) + ": expected a value in (0, 1]";
    return false;
  }
  if (!(clip_level > 0.0)) {
    *why = "ProbeExtractOptions::clip_level: expected a positive value";
    return false;
  }
  for (double v : camera_ypr_deg) {
    if (!std::isfinite(v) || std::abs(v) > 360.0) {
      *why = "ProbeExtractOptions::camera_ypr_deg: expected degrees in [-360, 360]";
      return false;
    }
  }
  return true;
}

nlohmann::json ExtractProbe(const ProbeExtractOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RefuseOutputsOverInputs({{"ProbeExtractOptions::out", o.out}}, {{"ProbeExtractOptions::image", o.image}});
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
    Log(o.image + ": ball at (" + std::to_string(m.circle.cx) + ", " + std::to_string(m.circle.cy) +
                           ") r " + std::to_string(m.circle.radius_px) + " px, " + std::to_string(m.samples.size()) +
                           " samples from " + std::to_string(m.pixels_used) + " pixels (" +
                           std::to_string(m.pixels_clipped) + " clipped), max luminance " +
                           std::to_string(m.max_luminance) + (m.max_luminance_clipped ? " (clipped)" : "") +
                           "; wrote " + o.out);
  nlohmann::json summary = doc;
  summary["out"] = o.out;
  return summary;
}

}  // namespace skycal::controllers
