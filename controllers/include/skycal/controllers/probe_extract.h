// The gray diffuse probe (Wood, Forza Horizon 3 skies, GDC) measured in a linear EXR
// photograph, as a library: the ball found (or given), its radiance binned by world surface
// normal (capture/probe.h, orthographic), written as a samples JSON for the fit's probes
// (FitControllerOptions::probes). `skycal probe-extract` parses its flags into
// ProbeExtractOptions, calls ExtractProbe and prints; the stress suite (bench/) calls it too.
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/probe.h"

namespace skycal::controllers {

struct ProbeExtractOptions {
  std::string image;                           // linear EXR (any size); required
  std::optional<capture::BallCircle> circle;   // the ball in pixels; empty: detected
  std::array<double, 3> camera_ypr_deg{};      // yaw, pitch, roll in degrees (capture/rig.h)
  double albedo = 0.18;                        // the ball's Lambertian albedo, (0, 1]
  double clip_level = std::numeric_limits<double>::infinity();  // pixels with a channel >= this are rejected
  std::string out;                             // SAMPLES.json, written atomically; required
  bool verbose = true;                         // its progress line on stderr ([probe-extract] ...); skycal bench turns it off

  // False and "ProbeExtractOptions::field ..." (with its value where one is set) in *why.
  bool IsValid(std::string* why) const;
};

// Measures the ball and writes `out`; returns the JSON summary (the samples document plus
// "out"). Throws skycal::Error (nothing written) when the options are not valid, the ball
// lies outside the image, is fully clipped or none is found; messages name
// ProbeExtractOptions fields, never flags.
nlohmann::json ExtractProbe(const ProbeExtractOptions& options);

}  // namespace skycal::controllers
