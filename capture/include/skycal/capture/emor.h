// Grossberg & Nayar's Empirical Model of Response ("Modeling the space of camera response
// functions", IEEE PAMI 26(10), 2004): a principal-component model of the 201 measured
// camera curves of their DoRF database, f = f0 + sum_i c_i h_i over irradiance E in [0, 1]
// (f(0) = 0 and f(1) = 1 for every c: each h_i is 0 at both ends). The bundled basis is
// datasets/response/emor_basis.csv (f0 and h1..h6 at E = i / 1023; datasets/README.md).
// Used by the merge's response prior (capture/src/emor_prior.h) and by the curves the
// benchmark and tests draw from the family (testing/response_shapes.h).
#pragma once
#include <array>
#include <string>
#include <vector>

namespace skycal::capture {

inline constexpr int kEmorSamples = 1024;  // E = i / 1023

struct EmorBasis {
  std::vector<double> f0;                // kEmorSamples values
  std::array<std::vector<double>, 6> h;  // h1..h6, kEmorSamples values each
};

// Reads the CSV (header E,f0,h1..h6, then kEmorSamples rows). Throws skycal::Error naming
// the file and, for a bad row, its number and what it holds.
EmorBasis ReadEmorBasis(const std::string& path);

// f0 + sum c_i h_i at the basis' samples.
std::vector<double> EmorCurve(const EmorBasis& basis, const std::array<double, 6>& c);

}  // namespace skycal::capture
