// gpu::ComputePipeline, the pipeline setup the sky and cloud renderers share: a dispatch
// computes what the shader says, buffers grow (and the descriptor set follows them), a
// pipeline is reusable, and bad bindings are refused. Values are small integers times a
// power of two, so float results are exact and compared with ==.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/gpu/compute_pipeline.h"

namespace skycal::spirv {
extern const uint32_t pipeline_probe[];
extern const size_t pipeline_probe_size;
extern const uint32_t texel_probe[];
extern const size_t texel_probe_size;
}  // namespace skycal::spirv

namespace skycal::gpu {
namespace {

struct Params {
  float scale[4];
  uint32_t count[4];
};

std::vector<float> RunScaled(ComputePipeline& p, const std::vector<float>& in, float scale) {
  const Params params{{scale, 0, 0, 0}, {static_cast<uint32_t>(in.size()), 0, 0, 0}};
  std::memcpy(p.Map(0, sizeof(params)), &params, sizeof(params));
  std::memcpy(p.Map(1, in.size() * sizeof(float)), in.data(), in.size() * sizeof(float));
  p.Map(2, in.size() * sizeof(float), /*host_readback=*/true);
  p.Flush(0);
  p.Flush(1);
  p.Dispatch(static_cast<uint32_t>((in.size() + 63) / 64), 1, 1);
  const float* out = static_cast<const float*>(p.Read(2));
  return std::vector<float>(out, out + in.size());
}

std::vector<float> Ramp(size_t n) {
  std::vector<float> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<float>(i % 1000);
  return v;
}

TEST(ComputePipeline, DispatchGrowsBuffersAndRebinds) {
  ComputePipeline p(VulkanContext::Shared(false), spirv::pipeline_probe, spirv::pipeline_probe_size,
                    {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                     VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                    {7});
  // Small, then 100x larger (new buffers: the descriptor set must follow), then small
  // again in the grown buffers (no shrink), each checked element by element.
  for (size_t n : {100u, 10000u, 37u}) {
    const std::vector<float> in = Ramp(n);
    const std::vector<float> out = RunScaled(p, in, 2.0f);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(out[i], in[i] * 2.0f + 7.0f) << "n=" << n << " i=" << i;
  }
  EXPECT_GE(p.Size(1), 10000 * sizeof(float));
}

TEST(ComputePipeline, TwoPipelinesShareOneContext) {
  auto ctx = VulkanContext::Shared(false);
  EXPECT_EQ(ctx.get(), VulkanContext::Shared(false).get());
  const std::vector<VkDescriptorType> types = {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                               VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
  ComputePipeline a(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, types, {1});
  ComputePipeline b(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, types, {3});
  const std::vector<float> in = Ramp(500);
  const std::vector<float> out_a = RunScaled(a, in, 0.5f), out_b = RunScaled(b, in, 4.0f);
  for (size_t i = 0; i < in.size(); ++i) {
    ASSERT_EQ(out_a[i], in[i] * 0.5f + 1.0f);
    ASSERT_EQ(out_b[i], in[i] * 4.0f + 3.0f);
  }
}

// Uniform texel buffers (the cloud textures): texelFetch reads the texel the host wrote,
// all four channels, at per-invocation indices; growing the buffer replaces its view.
TEST(ComputePipeline, TexelBufferReadsEveryChannelAndFollowsGrowth) {
  ComputePipeline p(VulkanContext::Shared(false), spirv::texel_probe, spirv::texel_probe_size,
                    {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                     VK_DESCRIPTOR_TYPE_STORAGE_BUFFER});
  for (uint32_t n : {100u, 5000u, 37u}) {
    const Params params{{1.0f, 16.0f, 256.0f, 4096.0f}, {n, 0, 0, 0}};
    std::memcpy(p.Map(0, sizeof(params)), &params, sizeof(params));
    float* texels = static_cast<float*>(p.Map(1, n * 4 * sizeof(float)));
    for (uint32_t i = 0; i < n; ++i) {
      for (uint32_t c = 0; c < 4; ++c) texels[4 * i + c] = static_cast<float>((i + c) % 8);
    }
    p.Map(2, n * sizeof(float), /*host_readback=*/true);
    p.Flush(0);
    p.Flush(1);
    p.Dispatch((n + 63) / 64, 1, 1);
    const float* out = static_cast<const float*>(p.Read(2));
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t t = n - 1 - i;
      const float expected = static_cast<float>(t % 8) + 16.0f * ((t + 1) % 8) + 256.0f * ((t + 2) % 8) +
                             4096.0f * ((t + 3) % 8);
      ASSERT_EQ(out[i], expected) << "n=" << n << " i=" << i;
    }
  }
}

TEST(ComputePipeline, RefusesBadBindings) {
  auto ctx = VulkanContext::Shared(false);
  EXPECT_THROW(ComputePipeline(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size,
                               {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}),
               Error);
  ComputePipeline p(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size,
                    {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                     VK_DESCRIPTOR_TYPE_STORAGE_BUFFER});
  EXPECT_THROW(p.Map(3, 16), Error);
  // Dispatch before every binding has a buffer: an error naming the binding, not a crash.
  p.Map(0, sizeof(Params));
  try {
    p.Dispatch(1, 1, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("binding 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skycal::gpu
