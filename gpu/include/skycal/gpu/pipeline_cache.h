// The Vulkan pipeline cache on disk (VkPipelineCache), so that a new process does not
// compile its shaders again: one file per device under $SKYCAL_PIPELINE_CACHE_DIR, else
// $XDG_CACHE_HOME/skycal, else ~/.cache/skycal; SKYCAL_PIPELINE_CACHE=0 turns it off.
//
// A driver trusts the bytes it is handed, so they are checked first: the file is skycal's
// 32-byte prefix (magic, format, the driver version, the payload's length and FNV-1a hash)
// and the driver's data, whose VkPipelineCacheHeaderVersionOne (Vulkan spec, "Pipeline
// Cache") must name this device's vendorID, deviceID and pipelineCacheUUID. A truncated,
// corrupt or foreign file is ignored with a warning (stderr and warnings()) and rewritten
// on the next save; a directory that cannot be written is warned about once. Files are
// written to a temporary name and renamed over the old one (no reader sees half a file).
//
// Include only from renderer sources and tests (vulkan.h; see vulkan_context.h).
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace skycal::gpu {

struct PipelineCacheKey {
  uint32_t vendor_id = 0, device_id = 0, driver_version = 0;
  uint8_t uuid[VK_UUID_SIZE] = {};
};

// The cache directory ("" when SKYCAL_PIPELINE_CACHE=0 or no home is known).
std::string PipelineCacheDir();
// <dir>/vulkan_pipelines_<vendor>_<device>.bin (hex ids): one file per device model.
std::string PipelineCachePath(const std::string& dir, const PipelineCacheKey& key);

// The file's driver payload, or false with the reason in *why (truncated, corrupt,
// another driver version, another device, ...).
bool CheckPipelineCacheFile(const std::vector<uint8_t>& file, const PipelineCacheKey& key,
                            std::vector<uint8_t>* payload, std::string* why);
// The file for `payload` (the driver's vkGetPipelineCacheData) under `key`.
std::vector<uint8_t> WrapPipelineCacheData(const std::vector<uint8_t>& payload, const PipelineCacheKey& key);

class PipelineCache {
 public:
  // Loads `path` (when not empty) into a new VkPipelineCache; never throws for the file.
  PipelineCache(VkDevice device, const PipelineCacheKey& key, std::string path);
  ~PipelineCache();
  PipelineCache(const PipelineCache&) = delete;
  PipelineCache& operator=(const PipelineCache&) = delete;

  VkPipelineCache handle() const { return cache_; }
  // Writes the driver's data when it differs from what the file holds (thread-safe).
  void Save();
  const std::string& path() const { return path_; }
  bool loaded() const { return loaded_; }  // the file was valid and handed to the driver
  std::vector<std::string> warnings() const;
  int saves() const;  // files written by this object

 private:
  void Warn(const std::string& text);
  VkDevice device_;
  PipelineCacheKey key_;
  std::string path_;
  VkPipelineCache cache_ = VK_NULL_HANDLE;
  bool loaded_ = false;
  bool write_failed_ = false;
  uint64_t saved_hash_ = 0;  // FNV-1a of the payload the file holds (0: none valid)
  int saves_ = 0;
  mutable std::mutex mutex_;
  std::vector<std::string> warnings_;
};

}  // namespace skycal::gpu
