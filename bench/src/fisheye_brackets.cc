#include "fisheye_brackets.h"

#include <algorithm>
#include <thread>

#include "skycal/testing/synthetic_brackets.h"
#include "skycal/testing/synthetic_fisheye.h"

namespace skycal::bench {

FisheyeBrackets WriteFisheyeBrackets(int scene_width, int fisheye, const std::string& dir) {
  FisheyeBrackets b;
  b.scene = synthetic::LoadBracketScene(scene_width, scene_width / 2, &b.scene_source);
  b.fisheye = fisheye;
  capture::RigCamera cam;
  cam.lens = synthetic::InscribedLens(capture::LensModel::kEquisolid, 180.0, fisheye);
  cam.width = cam.height = fisheye;
  cam.rotation = capture::RotationFromYawPitchRollDeg(0.0, 90.0, 0.0);
  synthetic::BracketSpec spec;
  spec.curve = synthetic::CameraCurve::kSrgb;
  const ImageRGB view = synthetic::RenderCameraView(b.scene, cam, std::max(2u, std::thread::hardware_concurrency()));
  b.paths = synthetic::WriteBracketsPng(synthetic::MakeSyntheticBrackets(view, spec), dir);
  b.exposure_times_s = spec.exposure_times_s;
  return b;
}

capture::CaptureOptions FisheyeCaptureOptions(const std::vector<std::string>& brackets, const std::vector<double>& times_s,
                                          const std::string& response, int width, const std::string& out) {
  capture::CaptureOptions co;
  co.brackets = brackets;
  co.exposure_times_s = times_s;
  co.merge.response = capture::ParseResponseModel(response, "response");
  co.lens.model = capture::LensModel::kEquisolid;
  co.lens.fov_deg = 180.0;
  co.camera_ypr_deg = std::array<double, 3>{0.0, 90.0, 0.0};
  co.width = width;
  co.height = width / 2;
  co.out = out;
  return co;
}

}  // namespace skycal::bench
