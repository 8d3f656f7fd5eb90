// Generation of the cloudscape's noise textures, after Schneider, "The Real-time
// Volumetric Cloudscapes of Horizon Zero Dawn" (SIGGRAPH 2015): a 128^3 RGBA base-shape
// volume (Perlin-Worley + three Worley fBm), a 32^3 RGB detail volume (Worley fBm) and a
// 128^2 RGB curl-noise texture. Every octave samples a whole number of lattice cells per
// tile, so every texture tiles (noise_primitives.h).
//
// Measured (Release, 2 threads, this 2-core machine, median of 5): 1.4 s of CPU for all
// three textures, so ~0.7 s wall on two free cores; the machine was never idle while this
// was measured: 3.0 s wall at load average 11. Nearly all of it is the base volume's 2M
// texels x (5 Worley + 5 Perlin octaves), about half each (perf).
#include "skycal/clouds/cloud_noise.h"

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "noise_primitives.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/sha256.h"

namespace skycal::clouds {
namespace {

using noise::WorleyGrid;

// Salts keep every noise independent of the others drawn from the same seed.
constexpr uint32_t kSaltBasePerlin = 0x100, kSaltBaseWorley = 0x200, kSaltDetailWorley = 0x300,
                   kSaltCurlStream = 0x400, kSaltCurlVertical = 0x500;

// Base volume: Perlin fBm from 4 cells per tile (32 texels a cell) over 5 octaves to 64
// cells (2 texels a cell: the finest an octave can be before it aliases), and Worley
// octaves at 4..64 cells: G uses 4/8/16, B 8/16/32, A 16/32/64 ("increasing frequencies").
constexpr int kBasePerlinCells = 4, kBasePerlinOctaves = 5;
constexpr int kBaseWorleyCells[] = {4, 8, 16, 32, 64};
// Detail volume: 2, 4, 8 cells base frequency; octaves above 16 cells (2 texels a cell in
// 32^3) are dropped and the remaining weights renormalised (noise::WorleyFbm).
constexpr int kDetailWorleyCells[] = {2, 4, 8, 16};
// Curl: stream functions of Perlin fBm from 4 cells per tile over 2 octaves (to 8 cells,
// 16 texels a cell): swirls smooth at texel scale, so the finite differences below are
// close to the derivatives. A derivative weighs octave k by 2^k, undoing fBm's 1/2^k: a
// third octave (tried) made the field as busy as its finest octave.
constexpr int kCurlCells = 4, kCurlOctaves = 2;

// An n^3 volume of `channels` channels; texel(x, y, z, t) writes texel (x, y, z)'s
// channels to t. Runs on 2 threads (the machine has 2 cores), interleaved z slices; each
// texel depends only on its coordinates, so the result is the same for any thread count.
template <typename TexelFn>
std::vector<float> FillVolume(int n, int channels, const TexelFn& texel) {
  std::vector<float> out(static_cast<size_t>(n) * n * n * channels);
  constexpr int kThreads = 2;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (int z = t; z < n; z += kThreads)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) texel(x, y, z, &out[((static_cast<size_t>(z) * n + y) * n + x) * channels]);
    });
  for (auto& th : threads) th.join();
  return out;
}

std::vector<WorleyGrid> MakeGrids(const int* cells, int count, uint64_t seed, uint32_t salt) {
  std::vector<WorleyGrid> grids;
  for (int k = 0; k < count; ++k) grids.emplace_back(cells[k], seed, salt + static_cast<uint32_t>(k));
  return grids;
}

// Texel centre i of an n-texel tile, in lattice cells of a `cells`-per-tile noise.
double Cell(int i, int n, int cells) { return (i + 0.5) * cells / n; }

// Inverted Worley of every grid at texel (x, y, z) of an n^3 volume.
void WorleyOctaves(const std::vector<WorleyGrid>& grids, int x, int y, int z, int n, float* out) {
  for (size_t k = 0; k < grids.size(); ++k) {
    const int c = grids[k].cells();
    out[k] = grids[k].Inverted(Cell(x, n, c), Cell(y, n, c), Cell(z, n, c));
  }
}

std::vector<float> GenerateBase(uint64_t seed) {
  constexpr int n = CloudNoise::kBaseSize, c = kBasePerlinCells;
  const auto grids = MakeGrids(kBaseWorleyCells, 5, seed, kSaltBaseWorley);
  return FillVolume(n, 4, [&](int x, int y, int z, float* t) {
    float w[5];
    WorleyOctaves(grids, x, y, z, n, w);
    const float perlin = noise::PeriodicPerlinFbm(Cell(x, n, c), Cell(y, n, c), Cell(z, n, c), c,
                                                  kBasePerlinOctaves, seed, kSaltBasePerlin);
    t[1] = noise::WorleyFbm(w + 0, 3);  // 4, 8, 16 cells
    t[2] = noise::WorleyFbm(w + 1, 3);  // 8, 16, 32
    t[3] = noise::WorleyFbm(w + 2, 3);  // 16, 32, 64
    t[0] = noise::PerlinWorley(noise::PerlinTo01(perlin), t[1]);
  });
}

std::vector<float> GenerateDetail(uint64_t seed) {
  constexpr int n = CloudNoise::kDetailSize;
  const auto grids = MakeGrids(kDetailWorleyCells, 4, seed, kSaltDetailWorley);
  return FillVolume(n, 3, [&](int x, int y, int z, float* t) {
    float w[4];
    WorleyOctaves(grids, x, y, z, n, w);
    t[0] = noise::WorleyFbm(w + 0, 3);  // 2, 4, 8 cells
    t[1] = noise::WorleyFbm(w + 1, 3);  // 4, 8, 16
    t[2] = noise::WorleyFbm(w + 2, 2);  // 8, 16 (32 would be 1 texel a cell)
  });
}

// A tileable n^2 grid of Perlin fBm (a potential), sampled at texel centres.
std::vector<double> Potential(int n, uint64_t seed, uint32_t salt) {
  std::vector<double> p(static_cast<size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      p[static_cast<size_t>(j) * n + i] = noise::PeriodicPerlinFbm(Cell(i, n, kCurlCells), Cell(j, n, kCurlCells),
                                                                   0.5, kCurlCells, kCurlOctaves, seed, salt);
  return p;
}

// Curl noise (Bridson et al., "Curl-Noise for Procedural Fluid Flow", SIGGRAPH 2007): the
// curl of a vector potential A(x, z) = (Ax, psi, Az) that does not vary with height y is
//   (-d psi/dz, dAx/dz - dAz/dx, d psi/dx)   in (x, y, z),
// so its horizontal part is the 2D curl of the stream function psi: divergence-free. The
// derivatives are central differences on the texel grid; the same stencil applied to the
// result gives a divergence of exactly 0 (difference operators commute), up to rounding.
std::vector<float> GenerateCurl(uint64_t seed) {
  constexpr int n = CloudNoise::kCurlSize;
  const std::vector<double> psi = Potential(n, seed, kSaltCurlStream);
  const std::vector<double> ax = Potential(n, seed, kSaltCurlVertical);
  const std::vector<double> az = Potential(n, seed, kSaltCurlVertical + 0x10);
  auto at = [&](const std::vector<double>& f, int i, int j) {
    return f[static_cast<size_t>(noise::Wrap(j, n)) * n + noise::Wrap(i, n)];
  };
  std::vector<double> v(static_cast<size_t>(n) * n * 3);
  double max_h = 0.0, max_v = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double* t = &v[(static_cast<size_t>(j) * n + i) * 3];
      t[0] = -(at(psi, i, j + 1) - at(psi, i, j - 1)) / 2.0;
      t[1] = (at(psi, i + 1, j) - at(psi, i - 1, j)) / 2.0;
      t[2] = (at(ax, i, j + 1) - at(ax, i, j - 1)) / 2.0 - (at(az, i + 1, j) - at(az, i - 1, j)) / 2.0;
      max_h = std::max({max_h, std::abs(t[0]), std::abs(t[1])});
      max_v = std::max(max_v, std::abs(t[2]));
    }
  // One scale for x and z keeps the pair divergence-free; the vertical part has its own.
  const double sh = max_h > 0 ? 1.0 / max_h : 0.0, sv = max_v > 0 ? 1.0 / max_v : 0.0;
  std::vector<float> out(v.size());
  for (size_t k = 0; k < v.size(); k += 3) {
    out[k + 0] = std::clamp(static_cast<float>(v[k + 0] * sh), -1.0f, 1.0f);
    out[k + 1] = std::clamp(static_cast<float>(v[k + 1] * sh), -1.0f, 1.0f);
    out[k + 2] = std::clamp(static_cast<float>(v[k + 2] * sv), -1.0f, 1.0f);
  }
  return out;
}

void AppendBytes(std::string& bytes, const std::vector<float>& values) {
  bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
}

}  // namespace

std::string CloudNoiseSha256(const CloudNoise& noise) {
  std::string bytes;
  bytes.reserve((noise.base.size() + noise.detail.size() + noise.curl.size()) * sizeof(float));
  AppendBytes(bytes, noise.base);
  AppendBytes(bytes, noise.detail);
  AppendBytes(bytes, noise.curl);
  return Sha256Hex(bytes);
}

CloudNoise GenerateCloudNoise(uint64_t seed) {
  CloudNoise noise;
  noise.seed = seed;
  noise.base = GenerateBase(seed);
  noise.detail = GenerateDetail(seed);
  noise.curl = GenerateCurl(seed);
  // Validated once here (every value is clamped above, so this guards the generator
  // itself); renders trust noise carrying its sha256 (ValidateCloudTextures).
  ValidateCloudNoise(noise, "generated cloud noise (seed " + std::to_string(seed) + ")");
  noise.sha256 = CloudNoiseSha256(noise);
  return noise;
}

float BaseTexel(const CloudNoise& noise, int x, int y, int z, int c) {
  constexpr int n = CloudNoise::kBaseSize;
  const size_t i = (static_cast<size_t>(noise::Wrap(z, n)) * n + noise::Wrap(y, n)) * n + noise::Wrap(x, n);
  return noise.base[i * 4 + c];
}

float DetailTexel(const CloudNoise& noise, int x, int y, int z, int c) {
  constexpr int n = CloudNoise::kDetailSize;
  const size_t i = (static_cast<size_t>(noise::Wrap(z, n)) * n + noise::Wrap(y, n)) * n + noise::Wrap(x, n);
  return noise.detail[i * 3 + c];
}

float CurlTexel(const CloudNoise& noise, int x, int y, int c) {
  constexpr int n = CloudNoise::kCurlSize;
  const size_t i = static_cast<size_t>(noise::Wrap(y, n)) * n + noise::Wrap(x, n);
  return noise.curl[i * 3 + c];
}

}  // namespace skycal::clouds
