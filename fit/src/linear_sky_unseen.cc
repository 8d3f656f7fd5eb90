// The rendered profile at the azimuths no pixel sees (LinearSkyOptions::unseen_profile).
//
// With tied rows a LUT column holds one value per table, and the game draws it at every
// azimuth through the tables' phases. A column that only a few azimuths read (the lowest
// degrees above a horizon masked by buildings and trees, a strip of open sea) gets the split
// between its tables from those pixels, and the game draws that split all round: at the
// sun's azimuth, behind the buildings, the Mie lobe of one column and the Rayleigh of the
// next make bright and dark stripes parallel to the horizon (bench/results/horizon_columns.md).
//
// The prior: at each 10-degree sector of azimuth where one of three consecutive columns is
// unseen, the change of the rendered radiance against the start's, ln(L / L0), is pulled
// toward a straight line across the three (its second difference) and, with kUnseenSlope
// times that weight, toward flat (the first difference of the upper two), so that a long
// unseen run does not extrapolate a slope. It is a prior on what the game draws there, not
// on each table's shape: the split between the tables stays the data's wherever the data see
// it, and a sky seen all round (every column read at every azimuth, or not at all) gets no
// term, so its fit is unchanged. One reference: the tied values; a day: per reference, the
// free rows around its sun.
#include <algorithm>
#include <array>
#include <cmath>

#include "linear_sky.h"
#include "linear_sky_normal.h"
#include "model_structure.h"
#include "skycal/core/latlong.h"
#include "skycal/render/sky_params.h"

namespace skycal::fit {
namespace {
// The first difference's weight over the second's. The second alone carries the slope of the
// change across a long unseen run (a horizon masked to 10 deg drew the unseen sun side far off
// a model sky's truth); 3 is the lightest flat pull that missed it by no more than the fit
// without any prior, and heavier ones cost the twilight photos' appearance
// (bench/results/horizon_columns.md).
constexpr double kUnseenSlope = 3.0;

// The two residuals' coefficients over the three columns, square-root weights in: the second
// difference (straight across the triple) and the first difference of the upper two (flat).
struct ProfileWeights {
  std::array<double, 3> second, first;
};
ProfileWeights Weights(double unseen_profile, int sectors) {
  const double w2 = std::sqrt(unseen_profile / sectors), w1 = std::sqrt(kUnseenSlope) * w2;
  return {{w2, -2.0 * w2, w2}, {0.0, -w1, w1}};
}

// Per column of a term, the tables' phases (Rayleigh, Cornette-Shanks at g, isotropic).
template <typename Term, typename Model>
std::array<std::array<double, 3>, 3> Phases(const Term& t, Model& m, double g) {
  std::array<std::array<double, 3>, 3> p;
  for (int i = 0; i < 3; ++i)
    p[i] = {t.phase_r[i], m.phase_cornette_shanks(t.mu[i], t.one_minus_mu[i], g), kIsotropicPhase};
  return p;
}
}  // namespace

std::vector<std::vector<char>> LinearSky::ColumnSectors(size_t ref) const {
  const int n_gamma = state_.preset.luts.grid.n_gamma;
  std::vector<std::vector<char>> seen(n_gamma, std::vector<char>(kSectors, 0));
  for (const Row& row : rows_) {
    if (row.ref != ref) continue;
    for (const Row::Node& n : row.nodes) {
      if (n.col < 0 || n.weight <= 0.0) continue;
      for (const Pixel& px : row.pixels) seen[n.col][static_cast<size_t>(px.x) * kSectors / width_] = 1;
    }
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

void LinearSky::BuildProfileTerms(const std::vector<Reference>& refs) {
  if (o_.unknowns == LinearUnknowns::kTiedRows) {
    AddProfileTerms(column_sectors_, refs[0]);
    return;
  }
  for (size_t r = 0; r < refs.size(); ++r) AddProfileTerms(ColumnSectors(r), refs[r]);
}

void LinearSky::AddProfileTerms(const std::vector<std::vector<char>>& sectors, const Reference& ref) {
  const auto& grid = state_.preset.luts.grid;
  const int n_gamma = grid.n_gamma;
  std::vector<int> sectors_seen(n_gamma, 0);
  for (int col = 0; col < n_gamma; ++col)
    for (char s : sectors[col]) sectors_seen[col] += s;
  NoLut none;
  StructureModel<double> m(none);
  auto p = render::SkyParamsFromPreset<StructureModel<double>::SkyParams>(state_.preset);
  const auto lr = m.lut_row(ref.sun_dir[1], p);
  const double wr[2] = {1.0 - lr.frow, lr.frow};
  for (int a = 0; a + 2 < n_gamma; ++a) {
    bool all_seen_somewhere = true, some_partly = false;
    for (int i = 0; i < 3; ++i) {
      all_seen_somewhere = all_seen_somewhere && sectors_seen[a + i] > 0;
      some_partly = some_partly || sectors_seen[a + i] < kSectors;
    }
    if (!all_seen_somewhere || !some_partly) continue;
    for (int k = 0; k < kSectors; ++k) {
      if (sectors[a][k] && sectors[a + 1][k] && sectors[a + 2][k]) continue;
      ProfileTerm t;
      const double longitude = latlong::Longitude((k + 0.5) * (width_ - 1) / kSectors, width_);
      for (int i = 0; i < 3; ++i) {
        const int col = a + i;
        // The node's elevation: sin(e) = (col / (n_gamma - 1))^2 (sky_model.glsl.h lut_col).
        const double q = static_cast<double>(col) / (n_gamma - 1);
        const auto v = latlong::Direction(std::asin(q * q), longitude);
        t.one_minus_mu[i] = OneMinusMu(v, ref.sun_dir);
        t.mu[i] = 1.0 - t.one_minus_mu[i];
        t.phase_r[i] = m.phase_rayleigh(t.mu[i]);
        for (int tb = 0; tb < state_.tables; ++tb) {
          if (o_.unknowns == LinearUnknowns::kTiedRows) {
            t.nodes[i][t.n_nodes[i]++] = {tb, (tb * n_gamma + col) * 3, 1.0};
            continue;
          }
          for (int dr = 0; dr < 2; ++dr)  // free rows: the two rows around the sun, blended
            if (wr[dr] > 0.0 && o_.row_fitted[lr.row0 + dr])
              t.nodes[i][t.n_nodes[i]++] = {tb, ((tb * grid.n_theta + lr.row0 + dr) * n_gamma + col) * 3, wr[dr]};
        }
      }
      profile_terms_.push_back(t);
    }
  }
}

void LinearSky::AddUnseenProfile(double g, const LinearSkySolution* linearize_at, NormalSystem* sys) const {
  const ProfileWeights w = Weights(o_.unseen_profile, kSectors);
  NoLut none;
  StructureModel<double> m(none);
  std::vector<std::array<std::array<double, 3>, 3>> phases;
  phases.reserve(profile_terms_.size());
  for (const ProfileTerm& t : profile_terms_) phases.push_back(Phases(t, m, g));
  // The terms of one column triple (its sectors, in order) share their unknowns: their normal
  // equations are summed in one dense block before they become triplets (36 times fewer
  // triplets than one set per term, which made the linear start several times slower).
  ProfileBlock block;
  for (int c = 0; c < 3; ++c)
    for (size_t k = 0; k < profile_terms_.size(); ++k) {
      AddProfileResidual(profile_terms_[k], phases[k], c, w.second, linearize_at, &block, sys);
      AddProfileResidual(profile_terms_[k], phases[k], c, w.first, linearize_at, &block, sys);
    }
  block.Flush(sys);
}

void LinearSky::ProfileBlock::Flush(NormalSystem* sys) {
  for (int i = 0; i < n; ++i) {
    sys->rhs[index[i]] += rhs[i];
    for (int j = 0; j < n; ++j) sys->triplets.emplace_back(index[i], index[j], normal[i * kMax + j]);
  }
  n = 0;
}

void LinearSky::AddProfileResidual(const ProfileTerm& t, const std::array<std::array<double, 3>, 3>& phase, int c,
                                   const std::array<double, 3>& s, const LinearSkySolution* linearize_at,
                                   ProfileBlock* block, NormalSystem* sys) const {
  std::array<int, ProfileBlock::kMax> index;
  std::array<double, ProfileBlock::kMax> coef;
  double target = 0.0;
  int n = 0;
  for (int i = 0; i < 3; ++i) {  // every column's unknowns, a zero weight too: one block per triple
    double l0 = 0.0, lc = 0.0;
    for (int j = 0; j < t.n_nodes[i]; ++j) {
      const ProfileTerm::Node& nd = t.nodes[i][j];
      l0 += phase[i][nd.table] * nd.weight * start_scale_ * initial_[nd.unknown_ch0 + c];
      if (linearize_at) lc += phase[i][nd.table] * nd.weight * linearize_at->values[nd.unknown_ch0 + c];
    }
    // Relative form L / L0 in the first solve; the log form ln(L / L0), linearised at the
    // current L, in the Gauss-Newton steps.
    const double norm = linearize_at ? lc : l0;
    if (!(norm > 0.0 && l0 > 0.0)) return;
    if (linearize_at) target -= s[i] * (std::log(lc / l0) - 1.0);
    for (int j = 0; j < t.n_nodes[i]; ++j) {
      const ProfileTerm::Node& nd = t.nodes[i][j];
      index[n] = nd.unknown_ch0 + c;
      coef[n++] = s[i] * phase[i][nd.table] * nd.weight / norm;
    }
  }
  if (block->n != n || !std::equal(index.begin(), index.begin() + n, block->index.begin())) {
    block->Flush(sys);
    block->n = n;
    std::copy(index.begin(), index.begin() + n, block->index.begin());
    std::fill(block->normal.begin(), block->normal.end(), 0.0);
    std::fill(block->rhs.begin(), block->rhs.end(), 0.0);
  }
  for (int i = 0; i < n; ++i) {
    block->rhs[i] += target * coef[i];
    for (int j = 0; j < n; ++j) block->normal[i * ProfileBlock::kMax + j] += coef[i] * coef[j];
  }
}

std::vector<UnseenProfileResidual> LinearSky::UnseenProfileResiduals(FitState* state) const {
  const auto& grid = state->preset.luts.grid;
  const ProfileWeights w = Weights(o_.unseen_profile, kSectors);
  const bool tied = o_.unknowns == LinearUnknowns::kTiedRows;
  NoLut none;
  StructureModel<double> m(none);
  std::vector<UnseenProfileResidual> out;
  for (const ProfileTerm& t : profile_terms_) {
    const auto phases = Phases(t, m, state->g);
    for (int c = 0; c < 3; ++c) {
      UnseenProfileResidual r;
      r.second = w.second;
      r.first = w.first;
      for (int i = 0; i < 3; ++i) {
        const auto& phase = phases[i];
        double l0 = 0.0;
        for (int j = 0; j < t.n_nodes[i]; ++j) {
          const ProfileTerm::Node& nd = t.nodes[i][j];
          const int u = nd.unknown_ch0 + c, col = (u / 3) % grid.n_gamma;
          const double start = phase[nd.table] * nd.weight * initial_[u];
          l0 += start;
          if (tied) {
            r.nodes[i].push_back({&state->log_delta[state->DeltaIndex(nd.table, col, c)], start});
          } else {
            const int row = (u / (3 * grid.n_gamma)) % grid.n_theta;
            r.nodes[i].push_back({&state->log_lut[state->Index(nd.table, row, col, c)], phase[nd.table] * nd.weight});
          }
        }
        r.log_l0[i] = std::log(l0);
      }
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace skycal::fit
