#include "noise_primitives.h"

#include <algorithm>
#include <cmath>

namespace skycal::clouds::noise {
namespace {

// A 64-bit finaliser (multiply/xor-shift avalanche, the SplitMix64 constants): every
// input bit flips about half the output bits, which a plain linear combination of the
// coordinates would not give.
uint64_t Mix64(uint64_t v) {
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ull;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebull;
  v ^= v >> 31;
  return v;
}

// Quintic fade 6t^5 - 15t^4 + 10t^3 (Perlin 2002): zero first and second derivatives at
// the lattice points, so the noise has no visible creases between cells.
double Fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double Lerp(double a, double b, double t) { return a + (b - a) * t; }

// Dot product of one of the 12 cube-edge gradients (Perlin 2002) with (x, y, z). A table
// rather than a switch: the hashed choice is random, so a switch mispredicts most calls.
double GradientDot(uint32_t h, double x, double y, double z) {
  static constexpr signed char kEdges[12][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                                {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                                {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}};
  const signed char* g = kEdges[(uint64_t{h} * 12u) >> 32];  // h scaled onto 0..11, no division
  return g[0] * x + g[1] * y + g[2] * z;
}

}  // namespace

uint64_t NoiseKey(uint64_t seed, uint32_t salt) { return Mix64(Mix64(seed) ^ salt); }

uint32_t HashLattice(int x, int y, int z, uint64_t key) {
  // The three 21-bit coordinates packed into one word, then one avalanche: distinct
  // points of one noise never share a packed word, so they hash independently.
  const uint64_t packed = uint64_t{static_cast<uint32_t>(x) & 0x1fffffu} |
                          (uint64_t{static_cast<uint32_t>(y) & 0x1fffffu} << 21) |
                          (uint64_t{static_cast<uint32_t>(z) & 0x1fffffu} << 42);
  return static_cast<uint32_t>(Mix64(key ^ packed) >> 32);
}

float PeriodicPerlin(double x, double y, double z, int period, uint64_t seed, uint32_t salt) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const double dx = x - fx, dy = y - fy, dz = z - fz;
  // Lattice indices wrap modulo the period: the gradient at cell `period` is the one at 0.
  const int ix = Wrap(static_cast<int>(fx), period), iy = Wrap(static_cast<int>(fy), period),
            iz = Wrap(static_cast<int>(fz), period);
  const int jx = Wrap(ix + 1, period), jy = Wrap(iy + 1, period), jz = Wrap(iz + 1, period);
  const uint64_t key = NoiseKey(seed, salt);
  auto g = [&](int cx, int cy, int cz, double ox, double oy, double oz) {
    return GradientDot(HashLattice(cx, cy, cz, key), ox, oy, oz);
  };
  const double u = Fade(dx), v = Fade(dy), w = Fade(dz);
  const double x00 = Lerp(g(ix, iy, iz, dx, dy, dz), g(jx, iy, iz, dx - 1, dy, dz), u);
  const double x10 = Lerp(g(ix, jy, iz, dx, dy - 1, dz), g(jx, jy, iz, dx - 1, dy - 1, dz), u);
  const double x01 = Lerp(g(ix, iy, jz, dx, dy, dz - 1), g(jx, iy, jz, dx - 1, dy, dz - 1), u);
  const double x11 = Lerp(g(ix, jy, jz, dx, dy - 1, dz - 1), g(jx, jy, jz, dx - 1, dy - 1, dz - 1), u);
  return static_cast<float>(Lerp(Lerp(x00, x10, v), Lerp(x01, x11, v), w));
}

float PeriodicPerlinFbm(double x, double y, double z, int period, int octaves, uint64_t seed, uint32_t salt) {
  double sum = 0.0, amplitude = 1.0, total = 0.0;
  int scale = 1;
  for (int k = 0; k < octaves; ++k) {
    // Octave k samples 2^k times as many cells over the same period: still periodic.
    sum += amplitude * PeriodicPerlin(x * scale, y * scale, z * scale, period * scale, seed,
                                      salt + static_cast<uint32_t>(k));
    total += amplitude;
    amplitude *= 0.5;
    scale *= 2;
  }
  return static_cast<float>(sum / total);
}

WorleyGrid::WorleyGrid(int cells, uint64_t seed, uint32_t salt, int depth)
    : cells_(cells), depth_(depth > 0 ? depth : cells), offsets_(static_cast<size_t>(cells) * cells * depth_ * 3) {
  const uint64_t key = NoiseKey(seed, salt);
  size_t i = 0;
  for (int z = 0; z < depth_; ++z)
    for (int y = 0; y < cells; ++y)
      for (int x = 0; x < cells; ++x) {
        // Three 10-bit fractions from one hash, one per axis: 1024 positions per axis in
        // the cell are plenty for textures of at most 4 texels per cell.
        const uint32_t h = HashLattice(x, y, z, key);
        offsets_[i++] = static_cast<float>((h & 1023u) + 0.5) / 1024.0f;
        offsets_[i++] = static_cast<float>(((h >> 10) & 1023u) + 0.5) / 1024.0f;
        offsets_[i++] = static_cast<float>(((h >> 20) & 1023u) + 0.5) / 1024.0f;
      }
}

float WorleyGrid::F1(double x, double y, double z) const {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const float px = static_cast<float>(x - fx), py = static_cast<float>(y - fy), pz = static_cast<float>(z - fz);
  // Neighbour cell indices, wrapped once here rather than 39 integer divisions per query.
  auto neighbours = [](double f, int n, int out[3]) {
    const int c = Wrap(static_cast<int>(f), n);
    out[0] = c == 0 ? n - 1 : c - 1;
    out[1] = c;
    out[2] = c + 1 == n ? 0 : c + 1;
  };
  int nx[3], ny[3], nz[3];
  neighbours(fx, cells_, nx);
  neighbours(fy, cells_, ny);
  neighbours(fz, depth_, nz);
  float best = 1e30f;
  for (int oz = 0; oz < 3; ++oz)
    for (int oy = 0; oy < 3; ++oy) {
      const float* row = &offsets_[(static_cast<size_t>(nz[oz]) * cells_ + ny[oy]) * cells_ * 3];
      for (int ox = 0; ox < 3; ++ox) {
        const float* p = row + nx[ox] * 3;
        // Query and point in the query cell's local frame: the neighbour's point sits at
        // its in-cell offset + (ox - 1, oy - 1, oz - 1), whichever wrapped cell drew it.
        const float dx = p[0] + static_cast<float>(ox - 1) - px, dy = p[1] + static_cast<float>(oy - 1) - py,
                    dz = p[2] + static_cast<float>(oz - 1) - pz;
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
    }
  return std::sqrt(best);
}

float WorleyGrid::Inverted(double x, double y, double z) const {
  return 1.0f - std::clamp(F1(x, y, z), 0.0f, 1.0f);
}

float WorleyFbm(const float* values, int count) {
  static constexpr float kWeights[3] = {0.625f, 0.25f, 0.125f};
  float sum = 0.0f, total = 0.0f;
  for (int k = 0; k < count && k < 3; ++k) {
    sum += kWeights[k] * values[k];
    total += kWeights[k];
  }
  return std::clamp(sum / total, 0.0f, 1.0f);
}

float PerlinTo01(float perlin) { return std::clamp(0.5f + 0.8f * perlin, 0.0f, 1.0f); }

float PerlinWorley(float perlin01, float worley) {
  return std::clamp(worley + perlin01 * (1.0f - worley), 0.0f, 1.0f);
}

}  // namespace skycal::clouds::noise
