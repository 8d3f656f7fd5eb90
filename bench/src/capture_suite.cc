// Suite `capture`: `skycal capture` (RunCaptureImpl) on 7 noisy 8-bit PNG brackets with an
// sRGB camera curve, seen by an up-looking equisolid 180 deg fisheye (4000x4000; 1000x1000
// with --quick) from a known lat-long scene (the real sunset when fetched, else the bundled
// preset; tests/synthetic_brackets.h). Grid: response model x output size. Time: the whole
// RunCaptureImpl (decode, merge, colour, unwrap, sun, masks, EXR write); error: rel RMSE of
// the frame against the scene above 10 deg elevation (the fisheye's rim excluded), after the
// best single exposure scale (a capture's absolute scale is the camera's, not the scene's).
#include <algorithm>
#include <thread>

#include "capture_verb.h"
#include "image_compare.h"
#include "skycal/capture/latlong_frame.h"
#include "suite_util.h"
#include "suites_internal.h"
#include "../../tests/synthetic_brackets.h"
#include "../../tests/synthetic_fisheye.h"

namespace skycal::bench {

Suite CaptureSuite() {
  Suite s;
  s.name = "capture";
  s.summary = "skycal capture: 7 fisheye PNG brackets -> lat-long frame: response x output size";
  s.error_metric = "rel RMSE vs the scene above 10 deg, after one exposure scale";
  s.error_axis = "rel RMSE vs the scene (one scale)";
  s.run = [](const SuiteOptions& o) {
    const int fisheye = o.quick ? 1000 : 4000, scene_w = o.quick ? 1024 : 2048;
    Grid grid;
    const std::vector<std::string> sizes = o.quick ? std::vector<std::string>{"512x256", "2048x1024"}
                                                   : std::vector<std::string>{"512x256", "1024x512", "2048x1024"};
    // Defaults: CaptureOptions (Debevec response, 2048x1024).
    grid.axes = {{"response", {"debevec", "srgb"}, "debevec"}, {"size", sizes, "2048x1024"}};
    std::string source;
    const ImageRGB scene = synthetic::LoadBracketScene(scene_w, scene_w / 2, &source);
    capture::RigCamera cam;
    cam.lens = synthetic::InscribedLens(capture::LensModel::kEquisolid, 180.0, fisheye);
    cam.width = cam.height = fisheye;
    cam.rotation = capture::RotationFromYawPitchRollDeg(0.0, 90.0, 0.0);
    synthetic::BracketSpec spec;
    spec.curve = synthetic::CameraCurve::kSrgb;
    const std::vector<std::string> paths = synthetic::WriteBracketsPng(
        synthetic::MakeSyntheticBrackets(synthetic::RenderCameraView(scene, cam, std::max(2u, std::thread::hardware_concurrency())), spec),
        o.scratch.string());
    o.Log("[capture] scene " + source + ", " + std::to_string(fisheye) + "x" + std::to_string(fisheye) + " fisheye, " +
          std::to_string(paths.size()) + " brackets");
    const int repeats = o.Repeats(o.quick ? 1 : 3);
    std::vector<CaseResult> out = RunGrid("capture", grid, o, [&](CaseResult& c) {
      cli::CaptureOptions co;
      co.brackets = paths;
      co.exposure_times_s = spec.exposure_times_s;
      co.merge.response = capture::ParseResponseModel(Get(c.settings, "response"), "response");
      co.lens.model = capture::LensModel::kEquisolid;
      co.lens.fov_deg = 180.0;
      co.camera_ypr_deg = {0.0, 90.0, 0.0};
      const std::string& size = Get(c.settings, "size");
      co.width = std::stoi(size.substr(0, size.find('x')));
      co.height = co.width / 2;
      co.out = (o.scratch / "capture_frame.exr").string();
      nlohmann::json summary;
      c.time = Measure([&] { summary = cli::RunCaptureImpl(co); }, o.quick ? 0 : o.warmup, repeats);
      const ImageRGB frame = capture::ReadLatLongFrame(co.out).radiance;
      c.error = RelRmse(scene, frame, 10.0, /*fit_scale=*/true);
      c.extra = {{"stages_ms", summary.value("stages", nlohmann::json())}, {"scene", source}, {"fisheye", fisheye}};
    });
    return out;
  };
  return s;
}

}  // namespace skycal::bench
