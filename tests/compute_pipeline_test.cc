// gpu::ComputePipeline, the pipeline setup the sky and cloud renderers share: a dispatch
// computes what the shader says, buffers grow (and the descriptor set follows them), a
// pipeline is reusable, and bad bindings are refused. Values are small integers times a
// power of two, so float results are exact and compared with ==.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/gpu/compute_pipeline.h"
#include "skycal/core/device_stats.h"
#include "skycal/gpu/pipeline_cache.h"

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
                               {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}),
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

const std::vector<VkDescriptorType> kProbeTypes = {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                                   VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

// Staged (device-local buffers, staging copies, readback copy) and direct give the same
// bits; the staged path copies only what was Flush()ed, so an unflushed binding keeps the
// device's previous content.
TEST(ComputePipeline, StagedAndDirectGiveTheSameBits) {
  auto ctx = VulkanContext::Shared(false);
  ComputePipeline direct(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, kProbeTypes, {5}, MemoryMode::kDirect);
  ComputePipeline staged(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, kProbeTypes, {5}, MemoryMode::kStaged);
  EXPECT_FALSE(direct.staged());
  EXPECT_TRUE(staged.staged());
  for (size_t n : {300u, 20000u, 64u}) {
    const std::vector<float> in = Ramp(n);
    const std::vector<float> a = RunScaled(direct, in, 3.0f), b = RunScaled(staged, in, 3.0f);
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), n * sizeof(float))) << "n=" << n;
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(b[i], in[i] * 3.0f + 5.0f);
  }
  EXPECT_EQ(staged.uploads(1), 3);
  EXPECT_EQ(staged.upload_bytes(1), static_cast<long long>((300 + 20000 + 64) * sizeof(float)));
  // Parameters re-flushed, the input not: the device keeps the input uploaded last.
  const Params params{{2.0f, 0, 0, 0}, {64, 0, 0, 0}};
  std::memcpy(staged.Map(0, sizeof(params)), &params, sizeof(params));
  staged.Flush(0);
  static_cast<float*>(staged.Map(1, 64 * sizeof(float)))[0] = 999.0f;  // written, never flushed
  staged.Dispatch(1, 1, 1);
  EXPECT_EQ(static_cast<const float*>(staged.Read(2))[0], 0.0f * 2.0f + 5.0f);
  EXPECT_EQ(staged.uploads(1), 3);
}

// The device time of a dispatch by timestamps: present (lavapipe writes them: 64 valid
// bits), positive, and no longer than the host's wall time around the Dispatch.
TEST(ComputePipeline, TimestampsGiveADeviceTimeWithinTheWallTime) {
  auto ctx = VulkanContext::Shared(false);
  if (ctx->timestamp_valid_bits() == 0) GTEST_SKIP() << "the device writes no timestamps";
  ComputePipeline p(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, kProbeTypes, {1});
  EXPECT_FALSE(p.last_gpu_ms().has_value());
  const std::vector<float> in = Ramp(1 << 20);
  RunScaled(p, in, 1.0f);  // first dispatch: grows buffers
  const Params params{{1.0f, 0, 0, 0}, {static_cast<uint32_t>(in.size()), 0, 0, 0}};
  std::memcpy(p.Map(0, sizeof(params)), &params, sizeof(params));
  p.Flush(0);
  const DeviceTimeTotals before = DeviceTimeSoFar();
  const auto t0 = std::chrono::steady_clock::now();
  p.Dispatch(static_cast<uint32_t>(in.size() / 64), 1, 1);
  const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(p.last_gpu_ms().has_value());
  EXPECT_GT(*p.last_gpu_ms(), 0.0);
  EXPECT_LE(*p.last_gpu_ms(), wall_ms);
  const DeviceTimeTotals after = DeviceTimeSoFar();
  EXPECT_EQ(after.timed_submits, before.timed_submits + 1);
  EXPECT_NEAR(after.gpu_ms - before.gpu_ms, *p.last_gpu_ms(), 1e-5);
}

// --- The pipeline cache on disk ---------------------------------------------------------

// Sets an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    const char* old = std::getenv(name);
    if (old) old_ = old;
    had_ = old != nullptr;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_) setenv(name_, old_.c_str(), 1);
    else unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

std::filesystem::path FreshDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("skycal-pipeline-cache-test-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::vector<uint8_t> ReadBytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const std::filesystem::path& p, const std::vector<uint8_t>& b) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// A new context (its own device and cache file) renders the probe; the result is checked.
struct CacheRun {
  bool loaded = false;
  std::vector<std::string> warnings;
  int saves = 0;
};
CacheRun RenderWithFreshContext() {
  CacheRun run;
  auto ctx = VulkanContext::Create(false);
  {
    ComputePipeline p(ctx, spirv::pipeline_probe, spirv::pipeline_probe_size, kProbeTypes, {9});
    const std::vector<float> in = Ramp(256);
    const std::vector<float> out = RunScaled(p, in, 2.0f);
    for (size_t i = 0; i < in.size(); ++i) EXPECT_EQ(out[i], in[i] * 2.0f + 9.0f);
  }
  if (const PipelineCache* c = ctx->pipeline_cache_file()) {
    run.loaded = c->loaded();
    run.warnings = c->warnings();
    run.saves = c->saves();
  }
  return run;
}

std::string CachePathFor(const std::filesystem::path& dir) {
  auto ctx = VulkanContext::Shared(false);
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(ctx->physical_device(), &props);
  PipelineCacheKey key;
  key.vendor_id = props.vendorID;
  key.device_id = props.deviceID;
  key.driver_version = props.driverVersion;
  std::memcpy(key.uuid, props.pipelineCacheUUID, VK_UUID_SIZE);
  return PipelineCachePath(dir.string(), key);
}

bool AnyWarningHas(const CacheRun& r, const std::string& text) {
  for (const std::string& w : r.warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

// Written on first use, loaded (without a warning) by the next process-like context.
TEST(PipelineCache, WrittenThenLoaded) {
  const auto dir = FreshDir("roundtrip");
  ScopedEnv env("SKYCAL_PIPELINE_CACHE_DIR", dir.string());
  const CacheRun first = RenderWithFreshContext();
  EXPECT_FALSE(first.loaded);
  EXPECT_TRUE(first.warnings.empty());
  EXPECT_GE(first.saves, 1);
  const std::string path = CachePathFor(dir);
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const CacheRun second = RenderWithFreshContext();
  EXPECT_TRUE(second.loaded);
  EXPECT_TRUE(second.warnings.empty());
  // No temporary left beside it.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

// Each damaged file: ignored with a warning that says why, the render still right, and the
// file rewritten so that the next context loads it.
TEST(PipelineCache, CorruptTruncatedAndForeignFilesAreIgnoredAndRewritten) {
  const auto dir = FreshDir("damaged");
  ScopedEnv env("SKYCAL_PIPELINE_CACHE_DIR", dir.string());
  RenderWithFreshContext();
  const std::string path = CachePathFor(dir);
  const std::vector<uint8_t> good = ReadBytes(path);
  ASSERT_GE(good.size(), 64u);
  struct Damage {
    std::string name, expected_reason;
    std::vector<uint8_t> bytes;
  };
  std::vector<Damage> cases;
  cases.push_back({"truncated in the prefix", "truncated", std::vector<uint8_t>(good.begin(), good.begin() + 10)});
  cases.push_back({"truncated payload", "truncated", std::vector<uint8_t>(good.begin(), good.end() - 7)});
  std::vector<uint8_t> flipped = good;
  flipped[good.size() - 1] ^= 0x5a;
  cases.push_back({"corrupt payload", "corrupt", flipped});
  cases.push_back({"not ours", "not a skycal pipeline cache", std::vector<uint8_t>(100, 0x42)});
  cases.push_back({"empty", "truncated", {}});
  // A well-formed file whose driver header names another device (vendorID changed, the
  // prefix's hash recomputed): only the Vulkan header check can refuse it.
  std::vector<uint8_t> payload(good.begin() + 32, good.end());
  payload[8] ^= 0xff;
  PipelineCacheKey key;
  std::memcpy(&key.driver_version, good.data() + 12, 4);
  cases.push_back({"foreign device", "another device", WrapPipelineCacheData(payload, key)});
  std::vector<uint8_t> version = good;
  version[12] ^= 1;  // the driver version in the prefix
  cases.push_back({"another driver version", "another driver version", version});
  for (const Damage& d : cases) {
    WriteBytes(path, d.bytes);
    const CacheRun run = RenderWithFreshContext();
    EXPECT_FALSE(run.loaded) << d.name;
    EXPECT_TRUE(AnyWarningHas(run, d.expected_reason)) << d.name << ": " << (run.warnings.empty() ? "" : run.warnings[0]);
    EXPECT_EQ(run.saves, 1) << d.name;
    EXPECT_TRUE(RenderWithFreshContext().loaded) << d.name << ": not rewritten";
  }
}

// A directory that cannot be made (its parent is a file): one warning, the render right.
TEST(PipelineCache, UnwritableDirectoryWarnsAndRenders) {
  const auto dir = FreshDir("unwritable");
  WriteBytes(dir / "a-file", {1, 2, 3});
  ScopedEnv env("SKYCAL_PIPELINE_CACHE_DIR", (dir / "a-file" / "cache").string());
  const CacheRun run = RenderWithFreshContext();
  EXPECT_EQ(run.saves, 0);
  ASSERT_EQ(run.warnings.size(), 1u);
  EXPECT_NE(run.warnings[0].find("not written"), std::string::npos) << run.warnings[0];
}

// SKYCAL_PIPELINE_CACHE=0: no cache object, no file.
TEST(PipelineCache, DisabledByEnvironment) {
  const auto dir = FreshDir("disabled");
  ScopedEnv env("SKYCAL_PIPELINE_CACHE_DIR", dir.string());
  ScopedEnv off("SKYCAL_PIPELINE_CACHE", "0");
  auto ctx = VulkanContext::Create(false);
  EXPECT_EQ(ctx->pipeline_cache_file(), nullptr);
  EXPECT_EQ(ctx->pipeline_cache(), VK_NULL_HANDLE);
  RenderWithFreshContext();
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

// The checks alone, on bytes made here.
TEST(PipelineCache, FileChecksNameTheFault) {
  PipelineCacheKey key;
  key.vendor_id = 0x10de;
  key.device_id = 0x2335;
  key.driver_version = 7;
  for (uint32_t i = 0; i < VK_UUID_SIZE; ++i) key.uuid[i] = static_cast<uint8_t>(i);
  std::vector<uint8_t> payload(48, 0xcd);
  const uint32_t header[4] = {32, VK_PIPELINE_CACHE_HEADER_VERSION_ONE, key.vendor_id, key.device_id};
  std::memcpy(payload.data(), header, 16);
  std::memcpy(payload.data() + 16, key.uuid, VK_UUID_SIZE);
  std::vector<uint8_t> out;
  std::string why;
  EXPECT_TRUE(CheckPipelineCacheFile(WrapPipelineCacheData(payload, key), key, &out, &why)) << why;
  EXPECT_EQ(out, payload);
  auto refused = [&](std::vector<uint8_t> p, const std::string& reason) {
    std::string w;
    std::vector<uint8_t> o;
    EXPECT_FALSE(CheckPipelineCacheFile(WrapPipelineCacheData(p, key), key, &o, &w)) << reason;
    EXPECT_NE(w.find(reason), std::string::npos) << w;
  };
  auto bad_uuid = payload;
  bad_uuid[20] ^= 1;
  refused(bad_uuid, "another device");
  auto bad_version = payload;
  bad_version[4] = 2;
  refused(bad_version, "headerVersion 2");
  auto bad_size = payload;
  bad_size[0] = 200;
  refused(bad_size, "headerSize 200");
  refused(std::vector<uint8_t>(payload.begin(), payload.begin() + 20), "driver's header is truncated");
}

}  // namespace
}  // namespace skycal::gpu
