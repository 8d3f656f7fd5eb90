// The Vulkan compute renderer: one gpu::ComputePipeline (render/shaders/sky_latlong.comp),
// buffers reused between renders and grown on demand, one submit and fence wait per render.
// The LUT slice and the direction table are uploaded only when their content changes (a
// new sun row, a new size); the uniforms every render.
#include <cmath>
#include <cstring>
#include <iterator>
#include <vector>

#include "cpu_renderer.h"
#include "resolved_sky.h"
#include "sky_uniforms.h"
#include "skycal/core/error.h"
#include "skycal/gpu/compute_pipeline.h"
#include "skycal/gpu/vulkan_context.h"
#include "skycal/render/renderer_stats.h"

namespace skycal::spirv {
extern const uint32_t sky_latlong[];
extern const size_t sky_latlong_size;
}  // namespace skycal::spirv

namespace skycal::render {
namespace {

// Workgroup size (specialization constants 0, 1). The shader maps one image row to one
// workgroup (y = gl_WorkGroupID.y), so the second dimension must stay 1.
constexpr uint32_t kLocalX = 128, kLocalY = 1;
// Bindings of sky_latlong.comp.
enum Binding : uint32_t { kUniforms = 0, kLuts = 1, kOutput = 2, kTrig = 3 };
constexpr VkDescriptorType kBindingTypes[] = {
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

class VulkanSkyRenderer final : public SkyRenderer {
 public:
  explicit VulkanSkyRenderer(std::shared_ptr<gpu::VulkanContext> ctx)
      : ctx_(std::move(ctx)),
        pipeline_(ctx_, spirv::sky_latlong, spirv::sky_latlong_size, {std::begin(kBindingTypes), std::end(kBindingTypes)},
                  {kLocalX, kLocalY}) {}

  ImageRGB Render(const Preset& preset, const RenderRequest& request) override {
    const SkyParamsD params = ResolveSkyParams(preset, request);
    const SkyUniforms u = PackSkyUniforms(params, request.width, request.height);

    const int columns = preset.luts.grid.n_gamma;
    const size_t lut_bytes = 3 * static_cast<size_t>(kMaxLutColumns) * 4 * sizeof(float);
    if (columns > kMaxLutColumns) throw Error("Vulkan renderer: LUT has " + std::to_string(columns) + " columns, at most " + std::to_string(kMaxLutColumns) + " supported");
    const size_t out_bytes = static_cast<size_t>(request.width) * request.height * 3 * sizeof(float);
    const size_t trig_bytes = static_cast<size_t>(request.width + request.height) * 2 * sizeof(float);
    std::memcpy(pipeline_.Map(kUniforms, sizeof(SkyUniforms)), &u, sizeof(u));
    std::vector<float> slice(lut_bytes / sizeof(float), 0.0f);
    FillLutSlice(preset, params, slice.data());
    float* luts = static_cast<float*>(pipeline_.Map(kLuts, lut_bytes));
    if (slice != lut_slice_ || luts != luts_filled_) {
      std::memcpy(luts, slice.data(), lut_bytes);
      pipeline_.Flush(kLuts);
      lut_slice_ = std::move(slice);
      luts_filled_ = luts;
    }
    pipeline_.Map(kOutput, out_bytes, /*host_readback=*/true);
    float* trig = static_cast<float*>(pipeline_.Map(kTrig, trig_bytes));
    if (trig != trig_filled_ || trig_width_ != request.width || trig_height_ != request.height) {
      FillTrigTable(preset, request.width, request.height, trig);
    }
    pipeline_.Flush(kUniforms);

    static_assert(kLocalY == 1, "sky_latlong.comp renders one row per workgroup");
    pipeline_.Dispatch((request.width + kLocalX - 1) / kLocalX, request.height, 1);

    // One pass over the mapped memory (no zero-fill of a fresh vector first).
    ImageRGB image;
    image.width = request.width;
    image.height = request.height;
    const float* mapped = static_cast<const float*>(pipeline_.Read(kOutput));
    image.pixels.assign(mapped, mapped + out_bytes / sizeof(float));
    return image;
  }

  int ValidationMessages() const override { return ctx_->validation_messages(); }
  DeviceStats Stats() const {
    DeviceStats s;
    s.gpu_ms = pipeline_.last_gpu_ms();
    s.resource_uploads = pipeline_.uploads(kLuts) + pipeline_.uploads(kTrig);
    s.resource_upload_bytes = pipeline_.upload_bytes(kLuts) + pipeline_.upload_bytes(kTrig);
    s.staged = pipeline_.staged();
    return s;
  }
  std::string Describe() const override {
    return std::string("vulkan (") + ctx_->device_name() + (ctx_->validation_enabled() ? ", validation on" : "") + ")";
  }

 private:
  // The LUTs interpolated (in double, by the shared model's own hook) to this frame's sun
  // row position: one vec4 per table and column. Tables the variant does not use stay 0.
  void FillLutSlice(const Preset& preset, const SkyParamsD& params, float* dst) {
    const CpuLutSource source{&preset.luts};
    CpuSkyModel m(source);
    const auto lr = m.lut_row(params.sun_dir.y, params);
    const int columns = preset.luts.grid.n_gamma;
    const int tables = preset.variant == ModelVariant::kFfxvIso ? 3 : 2;
    for (int t = 0; t < 3; ++t) {
      for (int c = 0; c < columns; ++c) {
        float* v = dst + 4 * (t * columns + c);
        const auto texel = t < tables ? m.lut_column_texel(t, lr.row0, lr.frow, c) : glsl::Vec3<double>(0.0);
        v[0] = static_cast<float>(texel.x);
        v[1] = static_cast<float>(texel.y);
        v[2] = static_cast<float>(texel.z);
        v[3] = 0.0f;
      }
    }
  }

  // Per-row (sin, cos) of latitude then per-column (sin, cos) of longitude, in double
  // through the shared model's angle functions, rounded once to float. Refilled only when
  // the size or the buffer changes.
  void FillTrigTable(const Preset& preset, int width, int height, float* t) {
    const CpuLutSource source{&preset.luts};
    CpuSkyModel m(source);
    for (int y = 0; y < height; ++y) {
      const double lat = m.latlong_latitude(y, height);
      t[2 * y] = static_cast<float>(std::sin(lat));
      t[2 * y + 1] = static_cast<float>(std::cos(lat));
    }
    for (int x = 0; x < width; ++x) {
      const double lon = m.latlong_longitude(x, width);
      t[2 * (height + x)] = static_cast<float>(std::sin(lon));
      t[2 * (height + x) + 1] = static_cast<float>(std::cos(lon));
    }
    pipeline_.Flush(kTrig);
    trig_filled_ = t;
    trig_width_ = width;
    trig_height_ = height;
  }

  std::shared_ptr<gpu::VulkanContext> ctx_;
  gpu::ComputePipeline pipeline_;
  const float* trig_filled_ = nullptr;  // the trig buffer last filled (a regrown buffer is refilled)
  std::vector<float> lut_slice_;        // the LUT slice last uploaded
  const float* luts_filled_ = nullptr;  // the LUT buffer it went to
  int trig_width_ = 0, trig_height_ = 0;  // size the trig table was filled for
};

}  // namespace

DeviceStats RendererDeviceStats(const SkyRenderer& renderer) {
  const auto* vulkan = dynamic_cast<const VulkanSkyRenderer*>(&renderer);
  return vulkan ? vulkan->Stats() : DeviceStats{};
}

std::unique_ptr<SkyRenderer> CreateRenderer(Backend backend, const VulkanOptions& vk) {
  if (backend == Backend::kCpu) return CreateCpuRenderer();
  return std::make_unique<VulkanSkyRenderer>(gpu::VulkanContext::Shared(vk.validation));
}

}  // namespace skycal::render
