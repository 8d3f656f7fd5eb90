// The capture and stress suites' input: a known lat-long scene seen by an up-looking
// equisolid 180 deg fisheye, as 7 noisy 8-bit PNG brackets with an sRGB camera curve
// (testing/synthetic_brackets.h), and the capture options that read them back (private to
// skycal_bench).
#pragma once
#include <string>
#include <vector>

#include "skycal/capture/capture_pipeline.h"
#include "skycal/core/image.h"

namespace skycal::bench {

struct FisheyeBrackets {
  ImageRGB scene;            // the truth, scene_width x scene_width / 2
  std::string scene_source;  // the real sunset when fetched, else the bundled preset
  int fisheye = 0;           // square fisheye image size, pixels
  std::vector<std::string> paths;    // PNGs, shortest exposure first
  std::vector<double> exposure_times_s;
};

FisheyeBrackets WriteFisheyeBrackets(int scene_width, int fisheye, const std::string& dir);

// RunCapturePipeline's options for `brackets` (equisolid 180 deg, looking up), output
// width x width / 2 at `out`, response "debevec" or "srgb".
capture::CaptureOptions FisheyeCaptureOptions(const std::vector<std::string>& brackets, const std::vector<double>& times_s,
                                          const std::string& response, int width, const std::string& out);

}  // namespace skycal::bench
