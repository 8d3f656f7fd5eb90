// The on-disk cache of generated cloud noise: one file per (generator version, seed),
// written atomically and trusted only after its header and sha256 check out. Reading the
// 33 MB file and hashing it is cheaper than regenerating (measured on this machine, median
// of 5 at load average 11: 0.17 s CPU / 0.35 s wall to load and verify, against 1.4 s CPU /
// 3.0 s wall to generate).
//
// File layout (host byte order, little-endian on every platform skycal builds for):
//   bytes  0..7   magic "SKYCLDNZ"
//          8..11  uint32 generator version (kCloudNoiseVersion)
//         12..23  uint32 base, detail, curl sizes (128, 32, 128)
//         24..31  uint64 seed
//         32..95  sha256 of the payload, 64 lowercase hex digits
//         96..    payload: base, detail, curl floats in the contract order
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <utility>

#include <sys/stat.h>

#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/sha256.h"

namespace skycal::clouds {
namespace {

constexpr char kMagic[8] = {'S', 'K', 'Y', 'C', 'L', 'D', 'N', 'Z'};
constexpr size_t kHeaderBytes = 96;

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t sizes[3];
  uint64_t seed;
  char sha256[64];
};
static_assert(sizeof(Header) == kHeaderBytes, "cache header layout");

size_t BaseCount() { return size_t{CloudNoise::kBaseSize} * CloudNoise::kBaseSize * CloudNoise::kBaseSize * 4; }
size_t DetailCount() { return size_t{CloudNoise::kDetailSize} * CloudNoise::kDetailSize * CloudNoise::kDetailSize * 3; }
size_t CurlCount() { return size_t{CloudNoise::kCurlSize} * CloudNoise::kCurlSize * 3; }
size_t PayloadBytes() { return (BaseCount() + DetailCount() + CurlCount()) * sizeof(float); }

std::string CachePath(const std::string& dir, uint64_t seed) {
  return (std::filesystem::path(dir) /
          ("cloud_noise_v" + std::to_string(kCloudNoiseVersion) + "_seed" + std::to_string(seed) + ".bin"))
      .string();
}

std::string Serialize(const CloudNoise& noise) {
  Header h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kCloudNoiseVersion;
  h.sizes[0] = CloudNoise::kBaseSize;
  h.sizes[1] = CloudNoise::kDetailSize;
  h.sizes[2] = CloudNoise::kCurlSize;
  h.seed = noise.seed;
  std::memcpy(h.sha256, noise.sha256.data(), std::min<size_t>(noise.sha256.size(), sizeof h.sha256));
  std::string bytes(reinterpret_cast<const char*>(&h), sizeof h);
  bytes.reserve(kHeaderBytes + PayloadBytes());
  for (const auto* v : {&noise.base, &noise.detail, &noise.curl})
    bytes.append(reinterpret_cast<const char*>(v->data()), v->size() * sizeof(float));
  return bytes;
}

std::vector<float> Floats(const std::string& bytes, size_t offset, size_t count) {
  std::vector<float> v(count);
  std::memcpy(v.data(), bytes.data() + offset, count * sizeof(float));
  return v;
}

// Why the cache bytes cannot be trusted, or "" when `noise` now holds them.
std::string Parse(const std::string& bytes, uint64_t seed, CloudNoise* noise) {
  if (bytes.size() != kHeaderBytes + PayloadBytes())
    return std::to_string(bytes.size()) + " bytes, expected " + std::to_string(kHeaderBytes + PayloadBytes());
  Header h;
  std::memcpy(&h, bytes.data(), sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return "not a skycal cloud noise cache (bad magic)";
  if (h.version != kCloudNoiseVersion) return "generator version " + std::to_string(h.version);
  if (h.sizes[0] != CloudNoise::kBaseSize || h.sizes[1] != CloudNoise::kDetailSize ||
      h.sizes[2] != CloudNoise::kCurlSize)
    return "texture sizes differ from 128/32/128";
  if (h.seed != seed) return "seed " + std::to_string(h.seed) + ", expected " + std::to_string(seed);
  const std::string sha = Sha256Hex(std::string_view(bytes).substr(kHeaderBytes));
  if (sha != std::string(h.sha256, sizeof h.sha256)) return "sha256 of the payload does not match its header";
  noise->seed = seed;
  noise->base = Floats(bytes, kHeaderBytes, BaseCount());
  noise->detail = Floats(bytes, kHeaderBytes + BaseCount() * sizeof(float), DetailCount());
  noise->curl = Floats(bytes, kHeaderBytes + (BaseCount() + DetailCount()) * sizeof(float), CurlCount());
  // The checksum proves the bytes are the ones written, not that they are in range (a
  // cache written by a broken build): the values are validated once here, where renders
  // trust noise carrying its sha256 (ValidateCloudTextures). Throws: the caller warns and
  // regenerates.
  ValidateCloudNoise(*noise, "cloud noise cache");
  noise->sha256 = sha;
  return "";
}

void Warn(const std::string& message) { std::cerr << "skycal: warning: " << message << "\n"; }

// Writes the cache; a directory that cannot be made or written costs a warning only.
void TryWriteCache(const CloudNoise& noise, const std::string& dir, const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  try {
    WriteFileAtomically(path, Serialize(noise));
  } catch (const Error& e) {
    Warn("cloud noise cache not written (" + std::string(e.what()) + "); using the generated noise");
  }
}

}  // namespace

namespace {

CloudNoise LoadOrGenerateUncached(uint64_t seed, const std::string& cache_dir) {
  if (cache_dir.empty()) return GenerateCloudNoise(seed);
  const std::string path = CachePath(cache_dir, seed);
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    std::string why;
    try {
      CloudNoise noise;
      why = Parse(ReadFile(path), seed, &noise);
      if (why.empty()) return noise;
    } catch (const Error& e) {
      why = e.what();
    }
    Warn("cloud noise cache " + path + " is corrupt (" + why + "); regenerating it");
  }
  CloudNoise noise = GenerateCloudNoise(seed);
  TryWriteCache(noise, cache_dir, path);
  return noise;
}

// The cache file's identity (inode, size, modification time): a file replaced or edited
// since it was read is read again.
std::string FileIdentity(const std::string& path) {
  struct stat st {};
  if (path.empty() || ::stat(path.c_str(), &st) != 0) return "none";
  return std::to_string(st.st_ino) + ":" + std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) + "." +
         std::to_string(st.st_mtim.tv_nsec);
}

}  // namespace

// The last noise read, kept for the process: a calibration reads it for each step that marches
// (the statistics, the inversion, the lighting refit, the game's image, the day's
// predictions), and each read of the cache file means 34 MB read, hashed and range-checked.
std::shared_ptr<const CloudNoise> SharedCloudNoise(uint64_t seed, const std::string& cache_dir) {
  static std::mutex mutex;
  static std::optional<std::pair<std::string, std::shared_ptr<const CloudNoise>>> last;
  const std::string path = cache_dir.empty() ? std::string() : CachePath(cache_dir, seed);
  std::lock_guard<std::mutex> lock(mutex);
  const std::string key = std::to_string(seed) + "|" + path + "|" + FileIdentity(path);
  if (last && last->first == key) return last->second;
  auto noise = std::make_shared<const CloudNoise>(LoadOrGenerateUncached(seed, cache_dir));
  last.emplace(std::to_string(seed) + "|" + path + "|" + FileIdentity(path), noise);  // the file as written, if it was
  return noise;
}

CloudNoise LoadOrGenerateCloudNoise(uint64_t seed, const std::string& cache_dir) {
  return *SharedCloudNoise(seed, cache_dir);
}

std::string DefaultCloudNoiseCacheDir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && xdg[0] == '/') return (std::filesystem::path(xdg) / "skycal").string();
  const char* home = std::getenv("HOME");
  if (home && home[0] != '\0') return (std::filesystem::path(home) / ".cache" / "skycal").string();
  return "";
}

std::string UsableCloudNoiseCacheDir() {
  const std::string dir = DefaultCloudNoiseCacheDir();
  if (dir.empty()) return dir;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const bool from_xdg = xdg && xdg[0] == '/';
  // The directory that must exist: two levels above .cache/skycal, one above <xdg>/skycal's <xdg>.
  const std::filesystem::path anchor = std::filesystem::path(dir).parent_path().parent_path();
  std::error_code ec;
  if (std::filesystem::is_directory(anchor, ec)) return dir;
  Warn("cloud noise not cached: " + std::string(from_xdg ? "the parent of $XDG_CACHE_HOME, '" : "$HOME, '") +
       anchor.string() + "', is not a directory (it is not created); generating the noise in memory");
  return "";
}

}  // namespace skycal::clouds
