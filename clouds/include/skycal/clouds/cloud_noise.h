// The cloudscape's three noise textures (cloud_textures.h), generated from a seed and
// cached on disk. Generation is deterministic: the same seed gives the same bytes (and
// sha256) on every run and any thread count; kCloudNoiseVersion names the algorithm, so a
// change to it is a new version (and a new golden checksum in tests/cloud_noise_test.cc).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "skycal/clouds/cloud_textures.h"

namespace skycal::clouds {

// Bumped whenever the generator's output changes; part of the cache file's header and name
// so a cache written by another version is never read as this one's.
inline constexpr uint32_t kCloudNoiseVersion = 1;

// Generates all three textures (2 threads; 1.4 s of CPU in Release, ~0.7 s wall on two
// free cores, see cloud_noise.cc) and fills `sha256`. Ranges, each clamped explicitly:
//   base   R Perlin-Worley in [0, 1]; G, B, A inverted-Worley fBm in [0, 1] with base
//          frequencies 4, 8, 16 cells per tile;
//   detail R, G, B inverted-Worley fBm in [0, 1], base frequencies 2, 4, 8 cells per tile;
//   curl   R = x, G = z: the curl of a scalar stream function in the horizontal plane,
//          divergence-free; B = y: the vertical component of the same vector potential's
//          curl; scaled so the largest |R|,|G| (and separately |B|) is 1, in [-1, 1].
//          Curl texel (i, j) is world (x, z) = (i, j) in texel units.
CloudNoise GenerateCloudNoise(uint64_t seed);

// The sha256 (lowercase hex) of base, detail and curl bytes in that order (host floats,
// little-endian on every platform skycal builds for).
std::string CloudNoiseSha256(const CloudNoise& noise);

// Reads `<cache_dir>/cloud_noise_v<version>_seed<seed>.bin` when it is valid (header,
// sizes, seed and the payload's sha256 all match); otherwise generates, warns on stderr
// in one line naming the file when a cache existed but was corrupt or truncated, and
// writes the cache atomically. A cache directory that cannot be created or written is a
// warning, never an error: rendering goes on with the generated noise. An empty cache_dir
// (no home directory known) generates without a cache. The last noise read is kept for the
// process and returned again while its cache file is the same (inode, size, mtime).
CloudNoise LoadOrGenerateCloudNoise(uint64_t seed, const std::string& cache_dir);
// The same noise, shared rather than copied: what the pipelines hold (a copy of 34 MB costs
// more than a render at the fit's sizes).
std::shared_ptr<const CloudNoise> SharedCloudNoise(uint64_t seed, const std::string& cache_dir);

// $XDG_CACHE_HOME/skycal when XDG_CACHE_HOME is set and absolute (the XDG base-directory
// rule), else $HOME/.cache/skycal; "" when neither is known (then no cache is used).
std::string DefaultCloudNoiseCacheDir();

// DefaultCloudNoiseCacheDir() when the directory it is made under exists: $HOME for
// $HOME/.cache/skycal, the parent of $XDG_CACHE_HOME for $XDG_CACHE_HOME/skycal (the XDG
// spec lets a program create a missing XDG_CACHE_HOME, not the tree above it). Otherwise
// "" after one warning line on stderr naming the missing directory: a HOME pointing
// nowhere (a service account, a container) is never created, and the noise is generated
// in memory.
std::string UsableCloudNoiseCacheDir();

// Texels with wrap-around (texel N is texel 0, -1 is N - 1): exact reads for tests and for
// the CPU model's trilinear filtering. `c` is the channel (base 0..3, detail and curl 0..2).
float BaseTexel(const CloudNoise& noise, int x, int y, int z, int c);
float DetailTexel(const CloudNoise& noise, int x, int y, int z, int c);
float CurlTexel(const CloudNoise& noise, int x, int y, int c);

}  // namespace skycal::clouds
