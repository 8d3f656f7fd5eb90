// Suite `clouds-divergence`: how much of the naive march's cost HZD's optimisations remove,
// on lavapipe and on an ideal machine that branches per pixel (the 3x target of docs/benchmarks.md). Per
// march (naive, game, ...): the Vulkan render time at 512x256 (wall and process CPU time),
// and from the float CPU twin of the shader (same decisions per pixel) the work per pixel:
// march iterations (one density evaluation each), texel loads (a cheap base-only sample
// reads the weather and base textures; a full one adds the detail and curl reads), and the
// lockstep cost of SIMD groups of 8 and of 4 adjacent pixels of a row (a group runs until
// its last lane is done, each pass costing the whole loop body: the sum over groups of the
// group's most iterations x its lanes). bench/clouds_divergence.sh runs this suite in
// processes alternating LP_NATIVE_VECTOR_WIDTH=256 and 128 (lavapipe's 8- and 4-lane
// groups) and writes bench/results/clouds_divergence.md.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "cloud_scene.h"
#include "resolved_clouds.h"
#include "skycal/bench/timing.h"
#include "skycal/core/latlong.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

// The CPU texture source with a count of the texels read per texture: texel() is called
// once per channel (RGBA base 4, the others 3), packed() once per packed texel (a shader's
// texelFetch each).
struct CountingTextures {
  clouds::CpuCloudTextures inner;
  mutable std::array<long long, 6> calls{};  // by texture id (cloud_textures.glsl.h)
  CountingTextures(const clouds::CloudNoise& noise, const clouds::WeatherMap& map) : inner(noise, map) {}
  template <typename S>
  S texel(int texture, int index) const {
    ++calls[static_cast<size_t>(texture)];
    return inner.texel<S>(texture, index);
  }
  void packed(bool base_pairs, int texel, float out[4]) const {
    ++calls[base_pairs ? 4 : 5];
    inner.packed(base_pairs, texel, out);
  }
  // Texel loads so far (a vec4 texelFetch each on the GPU).
  long long Loads() const { return calls[0] / 4 + (calls[1] + calls[2] + calls[3]) / 3 + calls[4] + calls[5]; }
};

struct Work {
  double iterations = 0, loads = 0, lockstep8 = 0, lockstep4 = 0;
};

// The work of the march `m` at the request's size, pixel by pixel in the float twin.
Work CountWork(const CloudBenchScene& scene, clouds::CloudRenderRequest request) {
  using Model = model::CloudModel<float, CountingTextures>;
  const auto shade = clouds::CastCloudShade<Model::CloudShadeParams>(clouds::ResolveCloudShade(scene.View(), request));
  const CountingTextures textures(scene.noise, scene.weather);
  Model m(textures);
  const clouds::LatLongTrig trig = clouds::MakeLatLongTrig(request.width, request.height);
  Work w;
  std::vector<int> row(static_cast<size_t>(request.width));
  for (int y = 0; y < request.height; ++y) {
    const float cl = static_cast<float>(trig.cos_lat[static_cast<size_t>(y)]);
    for (int x = 0; x < request.width; ++x) {
      const Model::vec3 view(static_cast<float>(trig.sin_lon[static_cast<size_t>(x)]) * cl,
                             static_cast<float>(trig.sin_lat[static_cast<size_t>(y)]),
                             static_cast<float>(trig.cos_lon[static_cast<size_t>(x)]) * cl);
      row[static_cast<size_t>(x)] = m.cloud_march(view, shade).iterations;
      w.iterations += row[static_cast<size_t>(x)];
    }
    for (int lanes : {8, 4}) {
      double& sum = lanes == 8 ? w.lockstep8 : w.lockstep4;
      for (int x0 = 0; x0 < request.width; x0 += lanes) {
        const int x1 = std::min(x0 + lanes, request.width);
        sum += static_cast<double>(x1 - x0) * *std::max_element(row.begin() + x0, row.begin() + x1);
      }
    }
  }
  w.loads = static_cast<double>(textures.Loads());
  return w;
}

std::string DivergenceTable(const std::vector<CaseResult>& cases) {
  return "# clouds-divergence: march work per pixel and lavapipe time\n\n"
         "Work from the float CPU twin at the timed size (sums over pixels, millions); lockstep: sum over SIMD "
         "groups of adjacent pixels of a row of the group's most iterations x its lanes.\n\n" +
         CaseTable(cases, "-",
                   {{"CPU ms", [](const CaseResult& c) { return ExtraNumber(c, "cpu_time_ms"); }},
                    {"iterations M", [](const CaseResult& c) { return ExtraNumber(c, "iterations", 1e-6); }},
                    {"texel loads M", [](const CaseResult& c) { return ExtraNumber(c, "texel_loads", 1e-6); }},
                    {"lockstep 8 M", [](const CaseResult& c) { return ExtraNumber(c, "lockstep8_iterations", 1e-6); }},
                    {"lockstep 4 M", [](const CaseResult& c) { return ExtraNumber(c, "lockstep4_iterations", 1e-6); }},
                    {"device", [](const CaseResult& c) { return c.extra.value("device", std::string("-")); }}});
}

}  // namespace

Suite CloudsDivergenceSuite() {
  Suite s;
  s.name = "clouds-divergence";
  s.summary = "HZD cloud march work per pixel (float twin) and lavapipe time at 512x256: naive vs game (run under LP_NATIVE_VECTOR_WIDTH=256/128)";
  s.error_metric = "none (time and work only)";
  s.error_axis = "-";
  s.pareto = false;
  s.markdown = DivergenceTable;
  s.run = [](const SuiteOptions& o) {
    const CloudBenchScene scene = LoadDefaultCloudyScene();
    Grid grid;
    grid.axes = {{"march", {"naive", "game", "no-cheap-light", "cheap-light-0.6"}, "game"}};
    const clouds::CloudRenderRequest req = CloudSuiteRequest(o.quick ? 64 : 512);
    std::unique_ptr<clouds::CloudRenderer> vulkan = clouds::CreateVulkanCloudRenderer();
    const int repeats = o.Repeats(o.quick ? 2 : 5);
    return RunGrid("clouds-divergence", grid, o, [&](CaseResult& c) {
      clouds::CloudRenderRequest r = req;
      r.march = CloudMarchVariant(Get(c.settings, "march"));
      TimeCloudRender(*vulkan, scene, r, o, repeats, c);
      const Work w = CountWork(scene, r);
      c.extra["iterations"] = w.iterations;
      c.extra["texel_loads"] = w.loads;
      c.extra["lockstep8_iterations"] = w.lockstep8;
      c.extra["lockstep4_iterations"] = w.lockstep4;
      c.extra["device"] = vulkan->Describe();
      c.extra["size"] = std::to_string(r.width) + "x" + std::to_string(r.height);
    });
  };
  return s;
}

}  // namespace skycal::bench
