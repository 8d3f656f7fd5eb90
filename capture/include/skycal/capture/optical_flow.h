// Dense motion vectors between two consecutive frames of a time-lapse, as
// Forza Horizon 3 shipped them (GDC talk "The Ambitious HDR Time-lapse Skies of Forza
// Horizon 3"): quarter resolution, forward (A to B) and backward (B to A) texture-space
// motion, 8 bits per component with each frame's per-component range in a JSON sidecar so
// the game can decode; plus a float EXR for tools.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/core/image.h"

namespace skycal::capture {

struct FlowOptions {
  std::string a, b;  // consecutive frames (uniform 2:1 lat-long EXRs of one size)
  std::string out;   // V.exr; V.png (8-bit RGBA) and V.json (ranges) beside it
  int scale = 4;     // the vectors' resolution: 1 / scale of the frames' (quarter: 4)
  bool IsValid(std::string* why) const;
};

// Forward flow of `b` relative to `a` (and nothing else): per pixel of the full frames,
// (dx, dy) in pixels such that a(x, y) ~ b(x + dx, y + dy). Log luminance tonemapped to 8
// bits over the two frames' common range, OpenCV DIS (medium preset), longitude wrapped;
// above 40 deg elevation from DIS in the zenith cap's polar view (zenith_cap.h; off only
// for the tests' control). Exposed for tests.
std::vector<float> DenseFlow(const ImageRGB& a, const ImageRGB& b, bool zenith_cap = true);

// The controller: reads frames a and b, writes out (float EXR), its 8-bit PNG and its JSON
// sidecar (all or none) and returns the sidecar plus the three paths. Progress on stderr.
nlohmann::json WriteFlowVectors(const FlowOptions& options);

}  // namespace skycal::capture
