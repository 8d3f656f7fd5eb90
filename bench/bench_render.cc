// Benchmark: median wall time of one 1024x512 lat-long render of the bundled default preset,
// Vulkan (lavapipe here) vs the CPU reference, after warm-up, measured in one run.
// Usage: bench_render [RESULTS.json [PRESET.json]]; default bench/results/render.json and
// the bundled preset.
#include <cstdio>
#include <iostream>

#include "bench_util.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

using namespace skycal;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/render.json";
  const std::string preset_path =
      argc > 2 ? argv[2] : std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json";
  const render::Preset preset = render::LoadPreset(preset_path);
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
  req.width = 1024;
  req.height = 512;

  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  std::cerr << "[bench render] vulkan: " << vulkan->Describe() << "\n[bench render] cpu: " << cpu->Describe() << "\n";
  const bench::Timing tv = bench::Measure([&] { vulkan->Render(preset, req); }, 5, 41);
  std::cerr << "[bench render] vulkan median " << tv.median_ms << " ms\n";
  const bench::Timing tc = bench::Measure([&] { cpu->Render(preset, req); }, 2, 21);
  std::cerr << "[bench render] cpu median " << tc.median_ms << " ms\n";
  // Pipeline creation and first dispatch (shader compile) are one-off costs, shown apart.
  const auto t0 = std::chrono::steady_clock::now();
  auto fresh = render::CreateRenderer(render::Backend::kVulkan);
  fresh->Render(preset, req);
  const double first_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  const nlohmann::json result = {
      {"benchmark", "render 1024x512 lat-long, default preset, sun elevation 35 deg"},
      {"machine", bench::MachineInfo()},
      {"vulkan", {{"device", vulkan->Describe()}, {"timing", tv.ToJson()}}},
      {"cpu", {{"device", cpu->Describe()}, {"timing", tc.ToJson()}}},
      {"vulkan_speedup_over_cpu", tc.median_ms / tv.median_ms},
      {"vulkan_first_render_ms_including_init", first_ms},
      {"targets", {{"vulkan_median_ms_max", 8.0}, {"speedup_min", 2.0}}},
      {"meets_targets", tv.median_ms <= 8.0 && tc.median_ms / tv.median_ms >= 2.0}};
  WriteJsonFileAtomically(out, result);
  std::cout << result.dump(2) << std::endl;
  return 0;
}
