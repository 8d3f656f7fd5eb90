// Benchmark: predicting the gray probe for 256 Fibonacci normals from a 512x256 sky of the
// bundled default preset (sun 35 deg): irradiance by direct quadrature (2 threads) vs SH-9
// (projection of the whole lat-long + evaluation at 256 normals), medians after warm-up,
// plus the sky render (Vulkan) and the whole PredictProbe for reference.
// Usage: bench_probe [RESULTS.json [PRESET.json]]; default bench/results/probe.json.
#include <iostream>

#include "bench_util.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

using namespace skycal;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results/probe.json";
  const std::string preset_path =
      argc > 2 ? argv[2] : std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json";
  const render::Preset preset = render::LoadPreset(preset_path);
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
  req.width = 512;
  req.height = 256;
  req.sun_disc = false;
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  const ImageRGB sky = vulkan->Render(preset, req);
  const auto normals = render::FibonacciSphere(256);

  std::vector<render::Rgb> q, s(normals.size());
  const bench::Timing tq = bench::Measure([&] { q = render::IrradianceQuadrature(sky, normals, 2); }, 2, 21);
  std::cerr << "[bench probe] quadrature median " << tq.median_ms << " ms\n";
  render::ShCoefficients sh{};
  const bench::Timing tp = bench::Measure([&] { sh = render::ProjectSh9(sky); }, 2, 21);
  const bench::Timing ts = bench::Measure(
      [&] {
        sh = render::ProjectSh9(sky);
        for (size_t i = 0; i < normals.size(); ++i) s[i] = render::ShIrradiance(sh, normals[i]);
      },
      2, 21);
  std::cerr << "[bench probe] SH-9 (projection + 256 evaluations) median " << ts.median_ms << " ms\n";
  const bench::Timing tr = bench::Measure([&] { vulkan->Render(preset, req); }, 2, 21);
  render::ProbePrediction p;
  const bench::Timing tall =
      bench::Measure([&] { p = render::PredictProbe(preset, req.sun_dir, normals, 0.18, *vulkan, 512); }, 2, 11);

  const nlohmann::json result = {
      {"benchmark", "gray probe prediction, 256 Fibonacci normals, 512x256 sky (no disc), default preset, sun 35 deg"},
      {"machine", bench::MachineInfo()},
      {"device", vulkan->Describe()},
      {"quadrature_2_threads", tq.ToJson()},
      {"sh9_projection_only", tp.ToJson()},
      {"sh9_projection_plus_256_evaluations", ts.ToJson()},
      {"sh9_speedup_over_quadrature", tq.median_ms / ts.median_ms},
      {"sky_render_vulkan_512x256", tr.ToJson()},
      {"predict_probe_total", tall.ToJson()},
      {"sh9_vs_quadrature_sky", {{"max_rel", p.sh_max_rel_error}, {"rms_rel", p.sh_rms_rel_error}}},
      {"sh9_vs_quadrature_total", {{"max_rel", p.sh_total_max_rel_error}, {"rms_rel", p.sh_total_rms_rel_error}}}};
  WriteJsonFileAtomically(out, result);
  std::cout << result.dump(2) << std::endl;
  return 0;
}
