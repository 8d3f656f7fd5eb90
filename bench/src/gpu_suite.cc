// Suite `gpu`: the Vulkan passes as a game runs them, warm (renderers, pipelines and
// textures kept; one untimed warm-up render): pass (the sky; the clouds alone) x size x
// march (the game's, the naive one) x the clouds' textures (texel buffers filtered by the
// shared source, or sampled images through the hardware filter). Each case: the wall time of one Render (readback
// included) and beside it the device time by timestamp queries (time_ms.gpu_median_ms),
// the memory path (staged or direct) and the uploads the timed renders made (0 when the
// textures stay on the device). The fresh-process side of the comparison is
// scripts/gpu_device_bench.sh. Error: none (a timing suite; 0).
#include <memory>

#include "cloud_scene.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "skycal/render/renderer_stats.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

Grid GpuGrid(bool quick) {
  Grid grid;
  grid.axes = {{"pass", {"sky", "clouds"}, "clouds"},
               {"size", quick ? std::vector<std::string>{"128x64", "256x128"} : std::vector<std::string>{"512x256", "2048x1024"},
                quick ? "128x64" : "512x256"},
               {"march", {"game", "naive"}, "game"},
               {"textures", {"buffers", "images"}, "buffers"}};
  grid.skip = [](const Settings& c) -> std::string {
    if (Get(c, "pass") == "sky" && Get(c, "march") != "game") return "the sky has no march";
    return Get(c, "pass") == "sky" && Get(c, "textures") != "buffers" ? "the sky reads its LUT from a buffer" : "";
  };
  return grid;
}

void Record(CaseResult& c, const DeviceStats& before, const DeviceStats& after) {
  c.extra["memory"] = after.staged ? "staged" : "direct";
  c.extra["sampled_images"] = after.sampled_images;
  c.extra["uploads_while_timed"] = after.resource_uploads - before.resource_uploads;
  c.extra["last_gpu_ms"] = after.gpu_ms ? nlohmann::json(*after.gpu_ms) : nlohmann::json(nullptr);
  c.error = 0.0;
}

}  // namespace

Suite GpuSuite() {
  Suite s;
  s.name = "gpu";
  s.summary = "Vulkan passes warm (sky; clouds alone, game and naive march): wall and device time per render";
  s.error_metric = "none (a timing suite: 0)";
  s.error_axis = "none";
  s.pareto = false;
  s.run = [](const SuiteOptions& o) {
    const CloudBenchScene scene = LoadDefaultCloudyScene();
    auto sky = render::CreateRenderer(render::Backend::kVulkan);
    std::unique_ptr<clouds::CloudRenderer> buffers =
        clouds::CreateVulkanCloudRenderer(false, clouds::CloudTextures::kBuffers);
    std::unique_ptr<clouds::CloudRenderer> images = clouds::CreateVulkanCloudRenderer(false, clouds::CloudTextures::kImages);
    const int repeats = o.Repeats(o.quick ? 3 : 5);
    return RunGrid("gpu", GpuGrid(o.quick), o, [&](CaseResult& c) {
      const std::string& size = Get(c.settings, "size");
      const int w = std::stoi(size.substr(0, size.find('x')));
      const auto sun = latlong::DirectionFromElevationAzimuthDeg(25.0, 40.0);
      if (Get(c.settings, "pass") == "sky") {
        render::RenderRequest rq;
        rq.sun_dir = sun;
        rq.width = w;
        rq.height = w / 2;
        sky->Render(scene.preset, rq);  // first render at this size: not timed
        const DeviceStats before = render::RendererDeviceStats(*sky);
        c.time = Measure([&] { sky->Render(scene.preset, rq); }, o.warmup, repeats);
        Record(c, before, render::RendererDeviceStats(*sky));
        c.extra["device"] = sky->Describe();
        return;
      }
      clouds::CloudRenderer* cloud = Get(c.settings, "textures") == "images" ? images.get() : buffers.get();
      clouds::CloudRenderRequest cr;
      cr.sun_dir = sun;
      cr.width = w;
      cr.height = w / 2;
      cr.march = CloudMarchVariant(Get(c.settings, "march"));
      cloud->Render(scene.View(), cr);
      const DeviceStats before = clouds::RendererDeviceStats(*cloud);
      c.time = Measure([&] { cloud->Render(scene.View(), cr); }, o.warmup, repeats);
      Record(c, before, clouds::RendererDeviceStats(*cloud));
      c.extra["device"] = cloud->Describe();
    });
  };
  return s;
}

}  // namespace skycal::bench
