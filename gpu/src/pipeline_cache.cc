#include "skycal/gpu/pipeline_cache.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include "skycal/gpu/vulkan_context.h"

namespace skycal::gpu {
namespace {

// skycal's prefix: magic, format version, the driver version, payload length and hash.
constexpr char kMagic[8] = {'S', 'K', 'Y', 'P', 'C', 'A', 'C', 'H'};
constexpr uint32_t kFormat = 1;
constexpr size_t kPrefixBytes = 32;
// VkPipelineCacheHeaderVersionOne: headerSize, headerVersion, vendorID, deviceID (uint32
// each), pipelineCacheUUID[16]: 32 bytes.
constexpr size_t kVulkanHeaderBytes = 16 + VK_UUID_SIZE;

uint64_t Fnv1a(const uint8_t* p, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

template <typename T>
T ReadAt(const std::vector<uint8_t>& b, size_t offset) {
  T v;
  std::memcpy(&v, b.data() + offset, sizeof(T));
  return v;
}

std::string Hex(uint32_t v) {
  char s[16];
  std::snprintf(s, sizeof(s), "%04x", v);
  return s;
}

// The driver's own header, checked field by field against this device.
bool CheckVulkanHeader(const std::vector<uint8_t>& payload, const PipelineCacheKey& key, std::string* why) {
  if (payload.size() < kVulkanHeaderBytes) {
    *why = "the driver's header is truncated (" + std::to_string(payload.size()) + " bytes)";
    return false;
  }
  const auto header_size = ReadAt<uint32_t>(payload, 0), version = ReadAt<uint32_t>(payload, 4);
  const auto vendor = ReadAt<uint32_t>(payload, 8), device = ReadAt<uint32_t>(payload, 12);
  if (header_size < kVulkanHeaderBytes || header_size > payload.size()) {
    *why = "headerSize " + std::to_string(header_size) + " is not in [32, " + std::to_string(payload.size()) + "]";
    return false;
  }
  if (version != VK_PIPELINE_CACHE_HEADER_VERSION_ONE) {
    *why = "headerVersion " + std::to_string(version) + " is not VK_PIPELINE_CACHE_HEADER_VERSION_ONE";
    return false;
  }
  if (vendor != key.vendor_id || device != key.device_id ||
      std::memcmp(payload.data() + 16, key.uuid, VK_UUID_SIZE) != 0) {
    *why = "written by another device (vendorID " + Hex(vendor) + ", deviceID " + Hex(device) +
           ", or its pipelineCacheUUID, differs from this device's " + Hex(key.vendor_id) + ", " + Hex(key.device_id) + ")";
    return false;
  }
  return true;
}

std::vector<uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Temp file in the same directory, then rename: atomic on POSIX file systems.
bool WriteAtomically(const std::string& path, const std::vector<uint8_t>& bytes, std::string* why) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec) {
    *why = "cannot create its directory (" + ec.message() + ")";
    return false;
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      *why = "cannot write " + tmp;
      out.close();
      std::filesystem::remove(tmp, ec);
      return false;
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    *why = "cannot rename " + tmp + " (" + ec.message() + ")";
    std::filesystem::remove(tmp, ec);
    return false;
  }
  return true;
}

}  // namespace

std::string PipelineCacheDir() {
  const char* off = std::getenv("SKYCAL_PIPELINE_CACHE");
  if (off && std::string(off) == "0") return "";
  const char* dir = std::getenv("SKYCAL_PIPELINE_CACHE_DIR");
  if (dir && dir[0] != '\0') return dir;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && xdg[0] == '/') return (std::filesystem::path(xdg) / "skycal").string();
  const char* home = std::getenv("HOME");
  if (home && home[0] != '\0') return (std::filesystem::path(home) / ".cache" / "skycal").string();
  return "";
}

std::string PipelineCachePath(const std::string& dir, const PipelineCacheKey& key) {
  if (dir.empty()) return "";
  return (std::filesystem::path(dir) / ("vulkan_pipelines_" + Hex(key.vendor_id) + "_" + Hex(key.device_id) + ".bin"))
      .string();
}

bool CheckPipelineCacheFile(const std::vector<uint8_t>& file, const PipelineCacheKey& key,
                            std::vector<uint8_t>* payload, std::string* why) {
  if (file.size() < kPrefixBytes) {
    *why = "truncated (" + std::to_string(file.size()) + " bytes, less than skycal's 32-byte prefix)";
    return false;
  }
  if (std::memcmp(file.data(), kMagic, sizeof(kMagic)) != 0 || ReadAt<uint32_t>(file, 8) != kFormat) {
    *why = "not a skycal pipeline cache (magic or format differs)";
    return false;
  }
  if (ReadAt<uint32_t>(file, 12) != key.driver_version) {
    *why = "written by another driver version (" + std::to_string(ReadAt<uint32_t>(file, 12)) + ", this one " +
           std::to_string(key.driver_version) + ")";
    return false;
  }
  const auto bytes = ReadAt<uint64_t>(file, 16);
  if (bytes != file.size() - kPrefixBytes) {
    *why = "truncated or padded (" + std::to_string(file.size() - kPrefixBytes) + " payload bytes, the prefix says " +
           std::to_string(bytes) + ")";
    return false;
  }
  if (Fnv1a(file.data() + kPrefixBytes, bytes) != ReadAt<uint64_t>(file, 24)) {
    *why = "corrupt (the payload's FNV-1a hash differs from the prefix's)";
    return false;
  }
  payload->assign(file.begin() + kPrefixBytes, file.end());
  return CheckVulkanHeader(*payload, key, why);
}

std::vector<uint8_t> WrapPipelineCacheData(const std::vector<uint8_t>& payload, const PipelineCacheKey& key) {
  std::vector<uint8_t> file(kPrefixBytes + payload.size());
  const uint64_t bytes = payload.size(), hash = Fnv1a(payload.data(), payload.size());
  std::memcpy(file.data(), kMagic, sizeof(kMagic));
  std::memcpy(file.data() + 8, &kFormat, 4);
  std::memcpy(file.data() + 12, &key.driver_version, 4);
  std::memcpy(file.data() + 16, &bytes, 8);
  std::memcpy(file.data() + 24, &hash, 8);
  if (!payload.empty()) std::memcpy(file.data() + kPrefixBytes, payload.data(), payload.size());
  return file;
}

PipelineCache::PipelineCache(VkDevice device, const PipelineCacheKey& key, std::string path)
    : device_(device), key_(key), path_(std::move(path)) {
  std::vector<uint8_t> payload;
  std::error_code ec;
  if (!path_.empty() && std::filesystem::exists(path_, ec)) {
    std::string why;
    if (CheckPipelineCacheFile(ReadAll(path_), key_, &payload, &why)) {
      loaded_ = true;
      saved_hash_ = Fnv1a(payload.data(), payload.size());
    } else {
      payload.clear();
      Warn("pipeline cache " + path_ + " ignored: " + why + "; it will be rewritten");
    }
  }
  VkPipelineCacheCreateInfo ci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
  ci.initialDataSize = payload.size();
  ci.pInitialData = payload.empty() ? nullptr : payload.data();
  VkResult r = vkCreatePipelineCache(device_, &ci, nullptr, &cache_);
  if (r != VK_SUCCESS && !payload.empty()) {  // the driver refused data that passed the checks
    Warn("pipeline cache " + path_ + " refused by the driver (" + VkResultName(r) + "); it will be rewritten");
    loaded_ = false;
    saved_hash_ = 0;
    ci.initialDataSize = 0;
    ci.pInitialData = nullptr;
    r = vkCreatePipelineCache(device_, &ci, nullptr, &cache_);
  }
  CheckVk(r, "vkCreatePipelineCache");
}

PipelineCache::~PipelineCache() {
  if (cache_) vkDestroyPipelineCache(device_, cache_, nullptr);
}

void PipelineCache::Warn(const std::string& text) {
  warnings_.push_back(text);
  std::cerr << "[vulkan] warning: " << text << std::endl;
}

std::vector<std::string> PipelineCache::warnings() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return warnings_;
}

int PipelineCache::saves() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return saves_;
}

void PipelineCache::Save() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (path_.empty() || write_failed_) return;
  size_t size = 0;
  if (vkGetPipelineCacheData(device_, cache_, &size, nullptr) != VK_SUCCESS) return;
  std::vector<uint8_t> payload(size);
  if (size == 0 || vkGetPipelineCacheData(device_, cache_, &size, payload.data()) != VK_SUCCESS) return;
  payload.resize(size);
  const uint64_t hash = Fnv1a(payload.data(), payload.size());
  if (hash == saved_hash_) return;
  std::string why;
  if (!WriteAtomically(path_, WrapPipelineCacheData(payload, key_), &why)) {
    write_failed_ = true;  // warned once per process and device
    Warn("pipeline cache " + path_ + " not written: " + why + " (set SKYCAL_PIPELINE_CACHE_DIR, or SKYCAL_PIPELINE_CACHE=0)");
    return;
  }
  saved_hash_ = hash;
  ++saves_;
}

}  // namespace skycal::gpu
