// `skycal probe-extract`: the gray diffuse probe (Wood, Forza Horizon 3 skies, GDC) measured in a linear EXR
// photograph: the ball found (or given), its radiance binned by world surface normal
// (capture/probe.h, orthographic), written as a samples JSON for `skycal fit --probe`.
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/probe.h"

namespace skycal::cli {

struct ProbeExtractOptions {
  std::string image;                           // linear EXR (any size)
  std::optional<capture::BallCircle> circle;   // --circle CX,CY,R; empty: detected
  std::array<double, 3> camera_ypr_deg{};      // --camera-rotation YAW,PITCH,ROLL (capture/rig.h)
  double albedo = 0.18;                        // the ball's Lambertian albedo, (0, 1]
  double clip_level = std::numeric_limits<double>::infinity();  // pixels with a channel >= this are rejected
  std::string out;                             // SAMPLES.json, written atomically
  bool verbose = true;                         // its progress line on stderr ([probe-extract] ...); skycal bench turns it off

  bool IsValid(std::string* why) const;
};

// Measures the ball and writes `out`; returns the JSON summary (the samples document plus
// pixel counts). Throws skycal::Error (nothing written) when the ball lies outside the
// image, is fully clipped or none is found.
nlohmann::json RunProbeExtractImpl(const ProbeExtractOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
ProbeExtractOptions ParseProbeExtractArgs(int argc, char** argv);
int RunProbeExtract(int argc, char** argv);

}  // namespace skycal::cli
