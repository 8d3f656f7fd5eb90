// The rendered profile at the azimuths no pixel sees (LinearSkyOptions::unseen_profile).
//
// With tied rows a LUT column holds one value per table, and the game draws it at every
// azimuth through the tables' phases. A column that only a few azimuths read (the lowest
// degrees above a horizon masked by buildings and trees, a strip of open sea) gets the split
// between its tables from those pixels, and the game draws that split all round: at the
// sun's azimuth, behind the buildings, the Mie lobe of one column and the Rayleigh of the
// next make bright and dark stripes parallel to the horizon (bench/results/horizon_columns.md).
//
// The prior: at each 10-degree sector of azimuth where a column is unseen, the change of the
// rendered radiance against the start's, ln(L / L0), varies linearly across three
// consecutive columns (its second difference is 0). It is a prior on what the game draws
// there, not on each table's shape: the split between the tables stays the data's wherever
// the data see it, and a sky seen all round (every column read at every azimuth, or not at
// all) gets no term, so its fit is unchanged.
#include <cmath>

#include "linear_sky.h"
#include "linear_sky_normal.h"
#include "model_structure.h"
#include "skycal/core/latlong.h"

namespace skycal::fit {

std::vector<std::vector<char>> LinearSky::ColumnSectors() const {
  const int n_gamma = state_.preset.luts.grid.n_gamma;
  std::vector<std::vector<char>> seen(n_gamma, std::vector<char>(kSectors, 0));
  for (const Row& row : rows_)
    for (const Row::Node& n : row.nodes) {
      if (n.col < 0 || n.weight <= 0.0) continue;
      for (const Pixel& px : row.pixels) seen[n.col][static_cast<size_t>(px.x) * kSectors / width_] = 1;
    }
  return seen;
}

int LinearSky::partly_seen_columns() const {
  int n = 0;
  for (const std::vector<char>& sectors : column_sectors_) {
    int seen = 0;
    for (char s : sectors) seen += s;
    n += seen > 0 && seen < kSectors;
  }
  return n;
}

void LinearSky::BuildProfileTerms(const std::array<double, 3>& sun_dir) {
  const int n_gamma = state_.preset.luts.grid.n_gamma;
  std::vector<int> sectors_seen(n_gamma, 0);
  for (int col = 0; col < n_gamma; ++col)
    for (char s : column_sectors_[col]) sectors_seen[col] += s;
  NoLut none;
  StructureModel<double> m(none);
  for (int a = 0; a + 2 < n_gamma; ++a) {
    bool all_seen_somewhere = true, some_partly = false;
    for (int i = 0; i < 3; ++i) {
      all_seen_somewhere = all_seen_somewhere && sectors_seen[a + i] > 0;
      some_partly = some_partly || sectors_seen[a + i] < kSectors;
    }
    if (!all_seen_somewhere || !some_partly) continue;
    for (int k = 0; k < kSectors; ++k) {
      if (column_sectors_[a][k] && column_sectors_[a + 1][k] && column_sectors_[a + 2][k]) continue;
      ProfileTerm t;
      const double longitude = latlong::Longitude((k + 0.5) * (width_ - 1) / kSectors, width_);
      for (int i = 0; i < 3; ++i) {
        // The node's elevation: sin(e) = (col / (n_gamma - 1))^2 (sky_model.glsl.h lut_col).
        const double q = static_cast<double>(a + i) / (n_gamma - 1);
        const auto v = latlong::Direction(std::asin(q * q), longitude);
        t.col[i] = a + i;
        t.one_minus_mu[i] = OneMinusMu(v, sun_dir);
        t.mu[i] = 1.0 - t.one_minus_mu[i];
        t.phase_r[i] = m.phase_rayleigh(t.mu[i]);
      }
      profile_terms_.push_back(t);
    }
  }
}

void LinearSky::AddUnseenProfile(double g, const LinearSkySolution* linearize_at, NormalSystem* sys) const {
  const int n_gamma = state_.preset.luts.grid.n_gamma;
  const double sqrt_w = std::sqrt(o_.unseen_profile / kSectors);
  const double second[3] = {1.0, -2.0, 1.0};
  NoLut none;
  StructureModel<double> m(none);
  for (const ProfileTerm& t : profile_terms_)
    for (int c = 0; c < 3; ++c) {
      int index[9];
      double coef[9], target = 0.0;
      int n = 0;
      bool usable = true;
      for (int i = 0; i < 3; ++i) {
        const double phase[3] = {t.phase_r[i], m.phase_cornette_shanks(t.mu[i], t.one_minus_mu[i], g), kIsotropicPhase};
        double l0 = 0.0, lc = 0.0;
        for (int tb = 0; tb < state_.tables; ++tb) {
          const int u = (tb * n_gamma + t.col[i]) * 3 + c;
          l0 += phase[tb] * start_scale_ * initial_[u];
          if (linearize_at) lc += phase[tb] * linearize_at->values[u];
        }
        // Relative form L / L0 in the first solve; the log form ln(L / L0), linearised at
        // the current L, in the Gauss-Newton steps.
        const double norm = linearize_at ? lc : l0;
        if (!(norm > 0.0) || !(l0 > 0.0)) usable = false;
        if (!usable) break;
        if (linearize_at) target -= sqrt_w * second[i] * (std::log(lc / l0) - 1.0);
        for (int tb = 0; tb < state_.tables; ++tb) {
          index[n] = (tb * n_gamma + t.col[i]) * 3 + c;
          coef[n++] = sqrt_w * second[i] * phase[tb] / norm;
        }
      }
      if (!usable) continue;
      for (int i = 0; i < n; ++i) {
        sys->rhs[index[i]] += target * coef[i];
        for (int j = 0; j < n; ++j) sys->triplets.emplace_back(index[i], index[j], coef[i] * coef[j]);
      }
    }
}

}  // namespace skycal::fit
