#include "skycal/capture/emor.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "skycal/core/error.h"

namespace skycal::capture {

EmorBasis ReadEmorBasis(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("EMoR basis: " + path + ": cannot be read");
  EmorBasis b;
  std::string line;
  std::getline(in, line);  // header: E,f0,h1..h6
  for (int row = 2; std::getline(in, line); ++row) {
    std::stringstream cells(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(cells, cell, ',')) v.push_back(std::strtod(cell.c_str(), nullptr));
    if (v.size() != 8) {
      throw Error("EMoR basis: " + path + ": row " + std::to_string(row) + ": need 8 columns (E,f0,h1..h6), got " +
                  std::to_string(v.size()));
    }
    b.f0.push_back(v[1]);
    for (int i = 0; i < 6; ++i) b.h[i].push_back(v[2 + i]);
  }
  if (b.f0.size() != kEmorSamples) {
    throw Error("EMoR basis: " + path + ": need " + std::to_string(kEmorSamples) + " rows, got " +
                std::to_string(b.f0.size()));
  }
  return b;
}

std::vector<double> EmorCurve(const EmorBasis& basis, const std::array<double, 6>& c) {
  std::vector<double> f = basis.f0;
  for (size_t k = 0; k < f.size(); ++k)
    for (int m = 0; m < 6; ++m) f[k] += c[m] * basis.h[m][k];
  return f;
}

}  // namespace skycal::capture
