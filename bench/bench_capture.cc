// Benchmark of `skycal capture` (the project's capture benchmark): median time to turn a
// 7-exposure bracket of 4000x4000 fisheye images into a 2048x1024 frame, and the time per
// stage (merge, colour, unwrap, sun, masks + write) from RunCaptureImpl's own stage timings.
// The scene: the real sunset (or the bundled preset) at 2048x1024 seen by an up-looking
// equisolid 180 deg fisheye at 4000x4000; 7 noisy 8-bit brackets with an sRGB camera curve
// written as PNG (preparation, timed separately, not part of the benchmark). Input colour
// space ACEScg so the colour stage does real work. Writes bench/results/capture.json (or argv[1]).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "bench_util.h"
#include "capture_verb.h"
#include "skycal/core/json_file.h"
#include "../tests/synthetic_brackets.h"
#include "../tests/synthetic_fisheye.h"

using namespace skycal;

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Peak resident set (kB) since the last ResetPeakRss (Linux; -1 where unavailable).
long long PeakRssKb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6));
  return -1;
}
bool ResetPeakRss() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  return static_cast<bool>(f);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/capture.json";
  constexpr int kFisheye = 4000, kWidth = 2048, kHeight = 1024, kWarmup = 1, kRuns = 3;
  const auto dir = std::filesystem::temp_directory_path() / "skycal-bench-capture";
  std::filesystem::create_directories(dir);

  // Preparation (not benchmarked).
  const auto tp = Clock::now();
  std::string source;
  std::vector<std::string> paths;
  std::vector<double> times;
  {
    const ImageRGB latlong = synthetic::LoadBracketScene(kWidth, kHeight, &source);
    std::cerr << "[bench capture] scene " << source << " " << kWidth << "x" << kHeight << " (" << MsSince(tp) << " ms)\n";
    capture::RigCamera cam;
    cam.lens = synthetic::InscribedLens(capture::LensModel::kEquisolid, 180.0, kFisheye);
    cam.width = cam.height = kFisheye;
    cam.rotation = capture::RotationFromYawPitchRollDeg(0.0, 90.0, 0.0);
    const ImageRGB view = synthetic::RenderCameraView(latlong, cam, std::max(2u, std::thread::hardware_concurrency()));
    std::cerr << "[bench capture] fisheye view " << kFisheye << "x" << kFisheye << " (" << MsSince(tp) << " ms)\n";
    synthetic::BracketSpec spec;
    spec.curve = synthetic::CameraCurve::kSrgb;
    const synthetic::SyntheticBrackets b = synthetic::MakeSyntheticBrackets(view, spec);
    paths = synthetic::WriteBracketsPng(b, dir.string());
    times = spec.exposure_times_s;
  }
  const double prep_ms = MsSince(tp);
  std::cerr << "[bench capture] preparation (scene, fisheye render, 7 brackets, PNG write): " << prep_ms << " ms\n";
  long long png_bytes = 0;
  for (const auto& p : paths) png_bytes += static_cast<long long>(std::filesystem::file_size(p));

  nlohmann::json result = {
      {"benchmark", "skycal capture (RunCaptureImpl): 7-exposure bracket of 4000x4000 fisheye PNGs -> 2048x1024 frame"},
      {"machine", bench::MachineInfo()},
      {"settings",
       {{"scene", source},
        {"scene_size", {kWidth, kHeight}},
        {"fisheye", "equisolid 180 deg, looking up, inscribed circle"},
        {"fisheye_size", {kFisheye, kFisheye}},
        {"brackets", static_cast<int>(paths.size())},
        {"bracket_format", "8-bit PNG, sRGB camera curve, noisy (synthetic_brackets.h defaults)"},
        {"bracket_png_bytes_total", png_bytes},
        {"exposure_times_s", times},
        {"input_colorspace", "ACEScg"},
        {"output_size", {kWidth, kHeight}},
        {"sun", "detection only (no --time/--lat/--lon)"},
        {"warmup", kWarmup},
        {"runs", kRuns}}},
      {"preparation_ms_not_benchmarked", prep_ms},
      {"stage_notes",
       "merge_ms includes PNG decoding and SHA-256 of the inputs; write_ms is the mask channels plus the EXR write "
       "(the 'mask' stage); total_ms is RunCaptureImpl's own t0..t5; wall_ms adds the option checks around it"}};

  nlohmann::json configs = nlohmann::json::object();
  const bool peak_resettable = ResetPeakRss();
  for (auto response : {capture::ResponseModel::kSrgb, capture::ResponseModel::kDebevec}) {
    const std::string name = response == capture::ResponseModel::kSrgb ? "srgb" : "debevec";
    cli::CaptureOptions o;
    o.brackets = paths;
    o.exposure_times_s = times;
    o.merge.response = response;
    o.lens.model = capture::LensModel::kEquisolid;
    o.lens.fov_deg = 180.0;
    o.camera_ypr_deg = {0.0, 90.0, 0.0};
    o.input_colorspace = "ACEScg";
    o.width = kWidth;
    o.height = kHeight;
    o.out = (dir / ("frame_" + name + ".exr")).string();
    std::map<std::string, std::vector<double>> stages;
    std::vector<double> wall;
    long long valid_pixels = 0;
    if (peak_resettable) ResetPeakRss();
    for (int i = 0; i < kWarmup + kRuns; ++i) {
      const auto t0 = Clock::now();
      const nlohmann::json j = cli::RunCaptureImpl(o);
      const double ms = MsSince(t0);
      valid_pixels = j["valid_pixels"].get<long long>();
      std::cerr << "[bench capture] " << name << (i < kWarmup ? " warm-up" : " run " + std::to_string(i - kWarmup + 1))
                << ": " << j["stages"].dump() << "\n";
      if (i < kWarmup) continue;
      wall.push_back(ms);
      for (const auto& [k, v] : j["stages"].items()) stages[k].push_back(v.get<double>());
    }
    nlohmann::json medians = nlohmann::json::object(), all = nlohmann::json::object();
    for (const auto& [k, v] : stages) {
      medians[k] = Median(v);
      all[k] = v;
    }
    configs[name] = {{"response", name},
                     {"median_ms", medians},
                     {"median_wall_ms", Median(wall)},
                     {"runs_ms", all},
                     {"valid_pixels", valid_pixels},
                     {"peak_rss_mb", peak_resettable ? PeakRssKb() / 1024.0 : -1.0}};
    std::cerr << "[bench capture] " << name << " medians: " << medians.dump() << ", peak RSS "
              << PeakRssKb() / 1024.0 << " MB\n";
  }
  result["configurations"] = configs;
  result["peak_rss_note"] = peak_resettable ? "per configuration, VmHWM reset after preparation (clear_refs 5)"
                                            : "VmHWM could not be reset: includes preparation";
  WriteJsonFileAtomically(out, result);
  std::filesystem::remove_all(dir);
  std::cerr << "[bench capture] wrote " << out << "\n";
  return 0;
}
