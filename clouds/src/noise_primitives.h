// Tileable noise primitives the cloud textures are built from: periodic gradient (Perlin)
// noise and periodic cellular (Worley) noise. Coordinates are in lattice cells; a noise
// with period P repeats every P cells along each axis, so a texture that samples P cells
// across its width tiles (texel N wraps to texel 0, cloud_textures.h).
//
// Sources: Perlin, "Improving Noise" (SIGGRAPH 2002) for the quintic fade and the 12
// edge gradients; Worley, "A Cellular Texture Basis Function" (SIGGRAPH 1996) for one
// jittered feature point per cell and the F1 distance. Both are written here from those
// descriptions; tiling comes from wrapping lattice/cell indices modulo the period.
#pragma once
#include <cstdint>
#include <vector>

namespace skycal::clouds::noise {

// A key per (seed, salt): the salt says which noise and which octave, so that every octave
// and channel draws independent values. Computed once per noise, not per lattice point.
uint64_t NoiseKey(uint64_t seed, uint32_t salt);
// 32 well-mixed bits from lattice coordinates in [0, 2^21) and a key.
uint32_t HashLattice(int x, int y, int z, uint64_t key);

// Perlin gradient noise at (x, y, z) in cells, periodic with `period` cells on each axis.
// Range about [-1, 1] (the 12 edge gradients bound it by ~1.04; callers clamp).
float PeriodicPerlin(double x, double y, double z, int period, uint64_t seed, uint32_t salt);

// Perlin fBm: `octaves` octaves at period, 2*period, ... with amplitudes 1, 1/2, ...,
// divided by the amplitude sum, so the result stays in about [-1, 1].
float PeriodicPerlinFbm(double x, double y, double z, int period, int octaves, uint64_t seed, uint32_t salt);

// Worley noise on a periodic grid of cells x cells x depth cells (depth = cells unless
// given), one feature point per cell at a hashed position inside it. The points are drawn
// once (a table), since a texture evaluates each octave at millions of texels. A 2D use
// (the weather map samples the plane z = 0.5) passes depth 1: a table of cells^2 points
// rather than cells^3, which at 1024 cells would be 12 GB.
class WorleyGrid {
 public:
  WorleyGrid(int cells, uint64_t seed, uint32_t salt, int depth = 0);
  int cells() const { return cells_; }
  // Distance from (x, y, z) (in cells) to the nearest feature point, in cells: F1 of
  // Worley 1996. With one point per cell the nearest one lies in the 3x3x3 block around
  // the query's cell, so the search visits those 27 cells only.
  // The query must lie in [0, cells) on x and y and [0, depth) on z (texel centres do).
  float F1(double x, double y, double z) const;
  // 1 - F1 clamped to [0, 1]: "inverted" Worley, bright at the feature points, the
  // billows of the Horizon Zero Dawn talk.
  float Inverted(double x, double y, double z) const;

 private:
  int cells_, depth_;
  std::vector<float> offsets_;  // cells^2 * depth * 3 in-cell positions in [0, 1)
};

// The fBm of Worley octaves the talk layers "like the standard Perlin fBm": weights
// 0.625, 0.25, 0.125 for octaves 1, 2, 4 times the base frequency (they sum to 1, so the
// result stays in [0, 1]). `values[k]` is the octave k value; `count` (1..3) octaves are
// used and their weights renormalised when fewer than 3 fit the texture.
float WorleyFbm(const float* values, int count);

// Perlin fBm (about [-0.6, 0.6] in practice: its octaves rarely align) mapped onto [0, 1]
// by 0.5 + 0.8 n, then clamped.
float PerlinTo01(float perlin);

// Perlin-Worley (Schneider, "The Real-time Volumetric Cloudscapes of Horizon Zero Dawn":
// Worley fBm "used as an offset to dilate Perlin noise"): Perlin in [0, 1] remapped from
// [0, 1] onto [worley, 1], i.e. worley + perlin * (1 - worley), in [0, 1]. It keeps
// Perlin's connected shapes and swells them into billows where the Worley is high.
float PerlinWorley(float perlin01, float worley);

// Wraps i into [0, n).
inline int Wrap(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

}  // namespace skycal::clouds::noise
