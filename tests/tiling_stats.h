// Seam statistics for tileable textures: is the pair of texels across the wrap (N-1, 0)
// just another neighbour pair? For each plane i along one axis, the mean |T(i+1) - T(i)|
// over the plane; plane N-1 pairs with plane 0 (the seam). In a tiling texture the seam
// plane is one more draw from the interior planes' distribution: its z-score against them
// stays within 4 (a Gaussian exceeds 4 sigma with probability 6e-5; "inside the interior
// [min, max]" was tried first and fails 1 time in N/2 by construction). A non-tiling seam
// pairs uncorrelated texels, several times a neighbour step: z of 108 to 153 in the
// negative control (cloud_noise_test); tiling seams measured |z| <= 2.6.
#pragma once
#include <cmath>
#include <functional>
#include <vector>

namespace skycal::testing {

// texel(i, a, b): i along the axis under test (0..n-1), a and b across the plane.
inline std::vector<double> PlaneStepMeans(const std::function<float(int, int, int)>& texel, int n, int na, int nb) {
  std::vector<double> means(n, 0.0);
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int b = 0; b < nb; ++b)
      for (int a = 0; a < na; ++a) sum += std::abs(texel((i + 1) % n, a, b) - texel(i, a, b));
    means[i] = sum / (static_cast<double>(na) * nb);
  }
  return means;
}

struct SeamVerdict {
  double seam = 0, interior_mean = 0, interior_sd = 0, z = 0;
  bool tiles() const { return std::abs(z) <= 4.0; }
};

inline SeamVerdict JudgeSeam(const std::vector<double>& means) {
  SeamVerdict v;
  v.seam = means.back();
  const size_t n = means.size() - 1;
  for (size_t i = 0; i < n; ++i) v.interior_mean += means[i] / n;
  for (size_t i = 0; i < n; ++i) v.interior_sd += (means[i] - v.interior_mean) * (means[i] - v.interior_mean) / (n - 1);
  v.interior_sd = std::sqrt(v.interior_sd);
  v.z = (v.seam - v.interior_mean) / v.interior_sd;
  return v;
}

}  // namespace skycal::testing
