// Suite `capture`: `skycal capture` (RunCapturePipeline) on 7 noisy 8-bit PNG brackets with an
// sRGB camera curve, seen by an up-looking equisolid 180 deg fisheye (4000x4000; 1000x1000
// with --quick) from a known lat-long scene (the real sunset when fetched, else the bundled
// preset; testing/synthetic_brackets.h). Grid: response model x output size. Time: the whole
// RunCapturePipeline (decode, merge, colour, unwrap, sun, masks, EXR write); error: rel RMSE of
// the frame against the scene (its area mean at the frame's nodes when the frame is coarser)
// above 10 deg elevation (the fisheye's rim excluded), after the
// best single exposure scale (a capture's absolute scale is the camera's, not the scene's).
#include "fisheye_brackets.h"
#include "image_compare.h"
#include "skycal/capture/latlong_frame.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

Suite CaptureSuite() {
  Suite s;
  s.name = "capture";
  s.summary = "skycal capture: 7 fisheye PNG brackets -> lat-long frame: response x output size";
  s.error_metric = "rel RMSE vs the scene (area mean at the frame's nodes) above 10 deg, after one exposure scale";
  s.error_axis = "rel RMSE vs the scene (one scale)";
  s.run = [](const SuiteOptions& o) {
    const int fisheye = o.quick ? 1000 : 4000, scene_w = o.quick ? 1024 : 2048;
    Grid grid;
    const std::vector<std::string> sizes = o.quick ? std::vector<std::string>{"512x256", "2048x1024"}
                                                   : std::vector<std::string>{"512x256", "1024x512", "2048x1024"};
    // Defaults: CaptureOptions (auto response, 2048x1024).
    grid.axes = {{"response", {"auto", "srgb"}, "auto"}, {"size", sizes, "2048x1024"}};
    const FisheyeBrackets b = WriteFisheyeBrackets(scene_w, fisheye, o.scratch.string());
    o.Log("[capture] scene " + b.scene_source + ", " + std::to_string(fisheye) + "x" + std::to_string(fisheye) +
          " fisheye, " + std::to_string(b.paths.size()) + " brackets");
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    std::vector<CaseResult> out = RunGrid("capture", grid, o, [&](CaseResult& c) {
      const std::string& size = Get(c.settings, "size");
      capture::CaptureOptions co = FisheyeCaptureOptions(b.paths, b.exposure_times_s, Get(c.settings, "response"),
                                                           std::stoi(size.substr(0, size.find('x'))),
                                                           (o.scratch / "capture_frame.exr").string());
      co.verbose = o.verb_logs;
      nlohmann::json summary;
      c.time = Measure([&] { summary = capture::RunCapturePipeline(co); }, o.quick ? 0 : o.warmup, repeats);
      const ImageRGB frame = capture::ReadLatLongFrame(co.out).radiance;
      // An output coarser than the scene is compared with the scene's area mean at its own
      // nodes: the unwrap filters (capture/rig.h), so a point-sampled finer truth would
      // charge it for detail its grid cannot hold (a real scene's trees and sun: 52% at
      // 512x256 against 8% at 2048x1024 before this).
      const ImageRGB truth = frame.width < b.scene.width ? AreaMeanAtNodes(b.scene, frame.width, frame.height) : b.scene;
      c.error = RelRmse(truth, frame, 10.0, /*fit_scale=*/true);
      c.extra = {{"stages_ms", summary.value("stages", nlohmann::json())}, {"scene", b.scene_source}, {"fisheye", fisheye}};
    });
    return out;
  };
  return s;
}

}  // namespace skycal::bench
