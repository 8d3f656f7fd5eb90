#include "linear_sky.h"
#include "linear_sky_normal.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <cstdlib>

#include "robust_residual.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/sky_params.h"
#include "model_structure.h"

namespace skycal::fit {
namespace {

using ModelD = StructureModel<double>;

ModelD::SkyParams GridParams(const FitState& st, double sun_height) {
  auto p = render::SkyParamsFromPreset<ModelD::SkyParams>(st.preset);
  p.sun_dir = glsl::Vec3<double>(0.0, sun_height, 0.0);
  return p;
}

// Non-positive entries are held at this fraction of their start rescaled to the data
// (start_scale_ x initial): relative to the data, so a reference 1000x darker than the
// preset is not held at a floor that is large for it.
constexpr double kFloorFraction = 1e-6;
// The pull toward the start (one reference) is relative to the start's entry, so a table the
// start makes vanishing was pinned to it: at a twilight sun (-3 to -8 deg) the start's Mie
// table is 1e-4 to 1e-16 of its Rayleigh, and the fit of a twilight photo drew no glow at all
// (`dawn` under a sun 6 deg down: per-pixel log RMSE 0.60 against 0.16). For a table vanishing
// at the reference's sun (FitState::kVanishingTable), the pull's centre is at least
// kPullFloorShare of the other's largest entry: a sky's size. 1e-2 for the share gave the same
// fits (bench/results/horizon_columns.md); tables that are not vanishing keep the pull as it
// was (a floor for every table moved daytime fits' weakly seen entries, and a partly cloudy
// refit downstream landed on a lighting with negative cloud radiance).
constexpr double kPullFloorShare = 1e-3;
constexpr double kActiveSetPenalty = 1e6; // stiffness of the hold, x the entry's diagonal
constexpr int kActiveSetRounds = 20;
// Unknowns one row's normal matrix spans: at most 3 tables x 2 x 2 nodes, and L_z.
constexpr int kMaxRowUnknowns = 13;

// Sum of the solid-angle weights of the pixels the solve uses (every stride-th pixel of
// every stride-th row) over all levels.
double TotalWeight(const std::vector<const FitLevel*>& levels, int w, int h, int stride) {
  double total_weight = 0.0;
  for (const FitLevel* lv : levels)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (x % stride == 0 && y % stride == 0) total_weight += lv->weight[static_cast<size_t>(y) * w + x];
  return total_weight;
}

std::string LevelName(const Reference& ref, size_t r) {
  return ref.path.empty() ? "reference " + std::to_string(r) : "reference '" + ref.path + "'";
}

std::string SizeOf(const FitLevel& lv) { return std::to_string(lv.width) + "x" + std::to_string(lv.height); }

// Every level must exist, match its reference and share the first level's size before any
// pixel is read: TotalWeight and the rows index each level with the first one's size.
void CheckLevels(const std::vector<const FitLevel*>& levels, const std::vector<Reference>& refs) {
  if (levels.empty() || levels.size() != refs.size()) {
    throw Error("LinearSky: " + std::to_string(levels.size()) + " levels for " + std::to_string(refs.size()) +
                " references (one level per reference, at least one)");
  }
  const FitLevel& first = *levels[0];
  for (size_t r = 0; r < levels.size(); ++r) {
    const FitLevel& lv = *levels[r];
    const size_t pixels = static_cast<size_t>(std::max(lv.width, 0)) * static_cast<size_t>(std::max(lv.height, 0));
    if (lv.width != first.width || lv.height != first.height) {
      throw Error("LinearSky: level sizes differ: " + LevelName(refs[r], r) + " gives a " + SizeOf(lv) + " level, " +
                  LevelName(refs[0], 0) + " a " + SizeOf(first) + " one (every level must have the same size)");
    }
    if (lv.weight.size() != pixels || lv.radiance.size() != 3 * pixels) {
      throw Error("LinearSky: the " + SizeOf(lv) + " level of " + LevelName(refs[r], r) + " holds " +
                  std::to_string(lv.weight.size()) + " weights and " + std::to_string(lv.radiance.size()) +
                  " radiance values (expected " + std::to_string(pixels) + " and " + std::to_string(3 * pixels) + ")");
    }
  }
}

}  // namespace

LinearSky::LinearSky(const FitState& state, const std::vector<const FitLevel*>& levels,
                     const std::vector<Reference>& refs, LinearSkyOptions options)
    : state_(state), o_(std::move(options)), n_refs_(static_cast<int>(refs.size())), width_(levels.empty() ? 0 : levels[0]->width) {
  CheckLevels(levels, refs);
  const auto& grid = state.preset.luts.grid;
  const int w = levels.at(0)->width, h = levels.at(0)->height;
  const bool single = refs.size() == 1;
  if (o_.unknowns != LinearUnknowns::kFreeRows && !single) throw Error("LinearSky: tied or per-row unknowns need one reference");
  if (o_.unknowns == LinearUnknowns::kFreeRows && static_cast<int>(o_.row_fitted.size()) != grid.n_theta) {
    throw Error("LinearSky: free rows need row_fitted for every LUT row");
  }
  // Unknown layout.
  const int per_table = o_.unknowns == LinearUnknowns::kTiedRows   ? grid.n_gamma
                        : o_.unknowns == LinearUnknowns::kFreeRows ? grid.n_theta * grid.n_gamma
                                                                   : h;
  num_unknowns_ = state.tables * per_table * 3;
  if (o_.fit_overcast) lz_index_ = num_unknowns_++;
  initial_.assign(num_unknowns_, 1.0);
  if (lz_index_ >= 0) initial_[lz_index_] = std::exp(state.log_overcast_zenith);

  const int stride = std::max(1, o_.stride);
  const double total_weight = TotalWeight(levels, w, h, stride);
  size_t sample = 0;
  for (size_t r = 0; r < refs.size(); ++r) {
    AddReferenceRows(r, *levels[r], refs[r], total_weight, &sample);
  }
  held_overcast_zenith_ = std::exp(state.log_overcast_zenith);
  if (o_.unknowns == LinearUnknowns::kFreeRows) {
    for (int t = 0; t < state.tables; ++t)
      for (int row = 0; row < grid.n_theta; ++row)
        for (int col = 0; col < grid.n_gamma; ++col)
          for (int c = 0; c < 3; ++c) initial_[((t * grid.n_theta + row) * grid.n_gamma + col) * 3 + c] = InitialLut(t, row, col, c);
  }
  std::vector<double> exposures;
  for (double le : state.log_exposure) exposures.push_back(std::exp(le));
  start_scale_ = StartScale(exposures, *MiePhases(state.g));
  if (single) pull_floor_ = PullFloor(refs[0]);
  if (o_.unknowns == LinearUnknowns::kTiedRows)
    column_sectors_ = o_.column_sectors.empty() ? ColumnSectors(0) : o_.column_sectors;
  if (o_.unseen_profile > 0.0 && o_.unknowns != LinearUnknowns::kPerImageRow) BuildProfileTerms(refs);
}

double LinearSky::InitialLut(int t, int row, int col, int ch) const {
  const auto& grid = state_.preset.luts.grid;
  const size_t table_size = state_.preset.luts.table_size();
  return std::exp(state_.initial_log_lut[t * table_size + ((static_cast<size_t>(row) * grid.n_gamma + col) * 3 + ch)]);
}

void LinearSky::AddReferenceRows(size_t r, const FitLevel& lv, const Reference& ref, double total_weight,
                                 size_t* sample) {
  NoLut none;
  ModelD m(none);
  const int w = lv.width, h = lv.height;
  const int stride = std::max(1, o_.stride);
  const auto p = GridParams(state_, ref.sun_dir[1]);
  const auto lr = m.lut_row(p.sun_dir.y, p);
  const double wr[2] = {1.0 - lr.frow, lr.frow};
  for (int y = 0; y < h; ++y) {
    if (y % stride != 0) continue;
    Row row;
    row.ref = r;
    row.y = y;
    row.first_sample = *sample;
    const auto v0 = latlong::PixelDirection(0, y, w, h);
    row.overcast_shape = OvercastShape(v0[1]);
    AddRowPixels(&row, lv, ref, total_weight, sample);
    if (row.pixels.empty()) continue;
    const auto lc = m.lut_col(v0[1], p);
    const double wc[2] = {1.0 - lc.fcol, lc.fcol};
    AddRowNodes(&row, h, lr.row0, wr, lc.col0, wc);
    rows_.push_back(std::move(row));
  }
}

void LinearSky::AddRowPixels(Row* row, const FitLevel& lv, const Reference& ref, double total_weight,
                             size_t* sample) {
  NoLut none;
  ModelD m(none);
  const int w = lv.width, h = lv.height, y = row->y;
  const int stride = std::max(1, o_.stride);
  for (int x = 0; x < w; ++x) {
    const size_t i = static_cast<size_t>(y) * w + x;
    if (lv.weight[i] <= 0.0 || x % stride != 0 || y % stride != 0) continue;
    const auto v = latlong::PixelDirection(x, y, w, h);
    Pixel px;
    px.x = x;
    px.sqrt_weight = std::sqrt(lv.weight[i] / total_weight);
    px.one_minus_mu = OneMinusMu(v, ref.sun_dir);
    px.mu = 1.0 - px.one_minus_mu;
    px.phase_r = m.phase_rayleigh(px.mu);
    for (int c = 0; c < 3; ++c) px.ref[c] = lv.radiance[3 * i + c];
    row->pixels.push_back(px);
    // Angle from |v - s|^2 = 2 (1 - cos), without acos' loss near 0.
    const double angle_deg = 2.0 * std::asin(std::min(1.0, 0.5 * std::sqrt(2.0 * px.one_minus_mu))) * 180.0 / M_PI;
    for (int c = 0; c < 3; ++c) {
      error_weight_.push_back(lv.weight[i] / total_weight);
      sun_angle_deg_.push_back(angle_deg);
    }
    *sample += 3;
  }
}

void LinearSky::AddRowNodes(Row* row, int h, int row0, const double wr[2], int col0, const double wc[2]) {
  const auto& grid = state_.preset.luts.grid;
  const int y = row->y;
  for (int t = 0; t < state_.tables; ++t) {
    if (o_.unknowns == LinearUnknowns::kPerImageRow) {
      const int u = ((t * h) + y) * 3;
      row->nodes.push_back({t, -1, u, 1.0});
      for (int c = 0; c < 3; ++c) {
        double v = 0.0;
        for (int dc = 0; dc < 2; ++dc)
          for (int dr = 0; dr < 2; ++dr) v += wc[dc] * wr[dr] * InitialLut(t, row0 + dr, col0 + dc, c);
        initial_[u + c] = v;
      }
      continue;
    }
    for (int dc = 0; dc < 2; ++dc) {
      if (wc[dc] <= 0.0) continue;
      const int col = col0 + dc;
      if (o_.unknowns == LinearUnknowns::kTiedRows) {
        const int u = (t * grid.n_gamma + col) * 3;
        row->nodes.push_back({t, col, u, wc[dc]});
        for (int c = 0; c < 3; ++c) {
          initial_[u + c] = wr[0] * InitialLut(t, row0, col, c) + wr[1] * InitialLut(t, row0 + 1, col, c);
        }
        continue;
      }
      for (int dr = 0; dr < 2; ++dr) {
        if (wr[dr] <= 0.0) continue;
        const int lut_row = row0 + dr;
        if (!o_.row_fitted[lut_row]) throw Error("LinearSky: a reference reads LUT row " + std::to_string(lut_row) + ", which is not fitted");
        const int u = ((t * grid.n_theta + lut_row) * grid.n_gamma + col) * 3;
        row->nodes.push_back({t, col, u, wc[dc] * wr[dr]});
      }
    }
  }
}

double LinearSky::StartScale(const std::vector<double>& exposures, const std::vector<double>& phase_m) const {
  LinearSkySolution start;
  start.values = initial_;
  double num = 0.0, den = 0.0;
  size_t pixel_index = 0;
  for (const Row& row : rows_) {
    const RowValues v = Blend(row, start);
    for (size_t p = 0; p < row.pixels.size(); ++p) {
      const Pixel& px = row.pixels[p];
      for (int c = 0; c < 3; ++c) {
        const double q = exposures[row.ref] * Model(row, px, c, phase_m[pixel_index + p], v) / px.ref[c];
        const double w = error_weight_[row.first_sample + 3 * p + c];
        num += w * q;
        den += w * q * q;
      }
    }
    pixel_index += row.pixels.size();
  }
  return den > 0.0 && num > 0.0 ? num / den : 1.0;
}

double LinearSky::Floor(int j) const { return kFloorFraction * start_scale_ * initial_[j]; }

std::vector<double> LinearSky::PullFloor(const Reference& ref) const {
  NoLut none;
  ModelD m(none);
  const auto p = GridParams(state_, ref.sun_dir[1]);
  const auto lr = m.lut_row(p.sun_dir.y, p);
  // The Rayleigh and Mie tables (the isotropic one, absent from many presets, as it was).
  std::array<std::array<double, 3>, 2> largest{};  // [table][channel]
  for (int t = 0; t < 2; ++t)
    for (int c = 0; c < 3; ++c)
      for (int col = 0; col < state_.preset.luts.grid.n_gamma; ++col)
        largest[t][c] = std::max(largest[t][c], (1.0 - lr.frow) * InitialLut(t, lr.row0, col, c) +
                                                    lr.frow * InitialLut(t, lr.row0 + 1, col, c));
  // Only a vanishing table's entries, and only those a pixel reads: the others have no
  // start of their own yet (initial_ 1) and take the nearest observed column's change after
  // the fit (fit_finish.h).
  std::vector<double> out(num_unknowns_, 0.0);
  for (const Row& row : rows_)
    for (const Row::Node& n : row.nodes)
      for (int c = 0; c < 3; ++c)
        if (n.table < 2 && FitState::Vanishing(largest[n.table][c], largest[1 - n.table][c]))
          out[n.unknown_ch0 + c] = kPullFloorShare * start_scale_ * largest[1 - n.table][c];
  return out;
}

std::shared_ptr<const std::vector<double>> LinearSky::MiePhases(double g) const {
  {
    std::lock_guard<std::mutex> lock(phase_cache_->mutex);
    if (phase_cache_->phases && phase_cache_->g == g) return phase_cache_->phases;
  }
  NoLut none;
  ModelD m(none);
  auto out = std::make_shared<std::vector<double>>();
  out->reserve(error_weight_.size() / 3);
  for (const Row& row : rows_)
    for (const Pixel& px : row.pixels) out->push_back(m.phase_cornette_shanks(px.mu, px.one_minus_mu, g));
  std::lock_guard<std::mutex> lock(phase_cache_->mutex);
  phase_cache_->g = g;
  phase_cache_->phases = out;
  return out;
}

LinearSky::RowValues LinearSky::Blend(const Row& row, const LinearSkySolution& s) const {
  RowValues v;
  for (const Row::Node& n : row.nodes)
    for (int c = 0; c < 3; ++c) v.lut[c][n.table] += n.weight * s.values[n.unknown_ch0 + c];
  v.lz = lz_index_ >= 0 ? s.values[lz_index_] : held_overcast_zenith_;
  return v;
}

double LinearSky::Model(const Row& row, const Pixel& px, int ch, double phase_m, const RowValues& v) const {
  const double w_o = state_.preset.overcast_weight;
  const double lut = px.phase_r * v.lut[ch][0] + phase_m * v.lut[ch][1] + kIsotropicPhase * v.lut[ch][2];
  return (1.0 - w_o) * lut + w_o * v.lz * row.overcast_shape;
}

// What a solve's data pass reads (Solve's arguments and the Mie phases at its g).
struct LinearSky::SolveInputs {
  const std::vector<double>& phase_m;
  const std::vector<double>& exposures;
  const std::vector<double>& robust_weights;
  const LinearSkySolution* linearize_at;
};

// Second moments of a row's pixel features (Rayleigh, Mie, isotropic phase, overcast
// shape) for one channel, upper triangle, and their products with the target.
struct LinearSky::FeatureMoments {
  double mom[4][4] = {};
  double mb[4] = {};
};

LinearSkySolution LinearSky::Solve(double g, const std::vector<double>& exposures,
                                   const std::vector<double>& robust_weights,
                                   const LinearSkySolution* linearize_at, bool with_cost) const {
  const std::shared_ptr<const std::vector<double>> phases = MiePhases(g);
  const SolveInputs in{*phases, exposures, robust_weights, linearize_at};
  NormalSystem sys = AccumulateData(in);
  // Regularisation. One reference (tied or per-row unknowns): a pull sqrt(lambda)
  // (x / (k x0) - 1) toward the start's shape at lambda = 1e-14, k the start's
  // least-squares scale on this data (for a vanishing table, k x0 at least pull_floor_), so
  // only entries no pixel sees feel it; the damping of the data's diagonal
  // (LinearSkyOptions::damping) conditions the rest. Several
  // references (free rows): the second difference of x / x0 along the sun zenith
  // (scale-free) links the rows between references, and the pull at prior_weight
  // separates the two rows around each sun, which the data see only blended; no damping
  // (toward zero it would fight the smoothness in exactly those directions).
  const bool free_rows = o_.unknowns == LinearUnknowns::kFreeRows;
  // Free rows linearised at a current solution xc (the day's Gauss-Newton steps): the
  // Ceres problem's log-space priors themselves, u = ln(x / x0) ~ x / xc - 1 + ln(xc / x0),
  // for entries not held at their floor (there a log prior would push back up by
  // ln(1 / floor) each step).
  const bool log_priors = free_rows && linearize_at != nullptr;
  const std::vector<char> was_held = log_priors ? linearize_at->held : std::vector<char>(num_unknowns_, 0);
  AddPriors(linearize_at, was_held, &sys);
  if (free_rows && o_.smoothness > 0.0) AddSmoothness(linearize_at, was_held, &sys);
  if (!profile_terms_.empty()) AddUnseenProfile(g, linearize_at, &sys);
  sys.normal = Eigen::SparseMatrix<double>(num_unknowns_, num_unknowns_);
  sys.normal.setFromTriplets(sys.triplets.begin(), sys.triplets.end());
  DampTowardStart(&sys);

  LinearSkySolution sol;
  sol.g = g;
  SolveActiveSet(sys, &sol);
  sol.overcast_zenith = lz_index_ >= 0 ? sol.values[lz_index_] : std::exp(state_.log_overcast_zenith);
  if (!with_cost) return sol;
  AddDataCost(in, &sol);
  return sol;
}

LinearSky::NormalSystem LinearSky::AccumulateData(const SolveInputs& in) const {
  // Rows are split between threads, each with its own triplets and right-hand side.
  NormalSystem parts[2];
  if (o_.threads > 1) {
    const size_t half = rows_.size() / 2;
    std::thread worker([&] { AccumulateRows(half, rows_.size(), in, &parts[1]); });
    AccumulateRows(0, half, in, &parts[0]);
    worker.join();
  } else {
    AccumulateRows(0, rows_.size(), in, &parts[0]);
    parts[1].rhs = Eigen::VectorXd::Zero(num_unknowns_);
  }
  NormalSystem sys;
  sys.triplets = std::move(parts[0].triplets);
  sys.triplets.reserve(sys.triplets.size() + parts[1].triplets.size() + 10 * static_cast<size_t>(num_unknowns_));
  sys.triplets.insert(sys.triplets.end(), parts[1].triplets.begin(), parts[1].triplets.end());
  sys.rhs = parts[0].rhs + parts[1].rhs;
  return sys;
}

void LinearSky::AccumulateRows(size_t row_begin, size_t row_end, const SolveInputs& in, NormalSystem* part) const {
  part->rhs = Eigen::VectorXd::Zero(num_unknowns_);
  // Reserved: growing ~10^6 triplets (a day) re-allocated and page-faulted ~10% of the
  // day's linear stage (perf).
  size_t count = 0;
  for (size_t ri = row_begin; ri < row_end; ++ri) {
    const size_t kk = rows_[ri].nodes.size() + (lz_index_ >= 0 ? 1 : 0);
    count += 3 * kk * kk;
  }
  part->triplets.reserve(count);
  for (size_t ri = row_begin; ri < row_end; ++ri) AccumulateRow(rows_[ri], in, part);
}

void LinearSky::AccumulateRow(const Row& row, const SolveInputs& in, NormalSystem* part) const {
  // Per row and channel: a dense normal matrix over the row's nodes (+ L_z), accumulated
  // in fixed arrays (a row reads at most 3 tables x 2 x 2 nodes) and scattered once.
  const double w_o = state_.preset.overcast_weight;
  const int k = static_cast<int>(row.nodes.size());
  const int kk = k + (lz_index_ >= 0 ? 1 : 0);
  // Every coefficient of a row is (bilinear weight) x (a pixel feature): the phase of
  // its table, or the overcast shape for L_z. So the row's normal matrix is the
  // weights' outer product times the features' second moments over its pixels (4 x 4
  // at most), accumulated per pixel instead of the nodes' 13 x 13.
  const RowValues v0 = in.linearize_at ? Blend(row, *in.linearize_at) : RowValues{};
  double coef[kMaxRowUnknowns];
  int feature[kMaxRowUnknowns];
  for (int j = 0; j < k; ++j) {
    coef[j] = (1.0 - w_o) * row.nodes[j].weight;
    feature[j] = row.nodes[j].table;
  }
  if (lz_index_ >= 0) {
    coef[k] = w_o * row.overcast_shape;
    feature[k] = 3;
  }
  for (int c = 0; c < 3; ++c) {
    const FeatureMoments fm = ChannelMoments(row, c, in, v0);
    double n[kMaxRowUnknowns][kMaxRowUnknowns], b[kMaxRowUnknowns];
    for (int i = 0; i < kk; ++i) {
      b[i] = coef[i] * fm.mb[feature[i]];
      for (int j = i; j < kk; ++j) {
        const int fa = std::min(feature[i], feature[j]), fb = std::max(feature[i], feature[j]);
        n[i][j] = coef[i] * coef[j] * fm.mom[fa][fb];
      }
    }
    auto global = [&](int j) { return j < k ? row.nodes[j].unknown_ch0 + c : lz_index_; };
    for (int i = 0; i < kk; ++i) {
      part->rhs[global(i)] += b[i];
      for (int j = 0; j < kk; ++j) part->triplets.emplace_back(global(i), global(j), i <= j ? n[i][j] : n[j][i]);
    }
  }
}

LinearSky::FeatureMoments LinearSky::ChannelMoments(const Row& row, int c, const SolveInputs& in,
                                                    const RowValues& v0) const {
  const double w_o = state_.preset.overcast_weight;
  const size_t pixel_index = row.first_sample / 3;
  const double exposure = in.exposures[row.ref];
  const double fixed_lz = lz_index_ >= 0 ? 0.0 : w_o * held_overcast_zenith_ * row.overcast_shape;
  FeatureMoments fm;
  for (size_t p = 0; p < row.pixels.size(); ++p) {
    const Pixel& px = row.pixels[p];
    const size_t smp = row.first_sample + 3 * p + c;
    const double rw = in.robust_weights.empty() ? 1.0 : in.robust_weights[smp];
    const double s = px.sqrt_weight * std::sqrt(rw);
    const double pm = in.phase_m[pixel_index + p];
    // Relative error: a . x / R - 1. Log error linearised at M0:
    // a . x / M0 - (1 - ln(k M0 / R)).
    double norm = px.ref[c], target = s;
    if (in.linearize_at) {
      const double m0 = exposure * Model(row, px, c, pm, v0);
      if (m0 > 0.0) {
        norm = m0;
        target = s * (1.0 - std::log(m0 / px.ref[c]));
      }
    }
    const double scale = s * exposure / norm;
    target -= scale * fixed_lz;
    const double f[4] = {scale * px.phase_r, scale * pm, scale * kIsotropicPhase, scale};
    for (int a = 0; a < 4; ++a) {
      fm.mb[a] += target * f[a];
      for (int b = a; b < 4; ++b) fm.mom[a][b] += f[a] * f[b];
    }
  }
  return fm;
}

void LinearSky::AddPriors(const LinearSkySolution* linearize_at, const std::vector<char>& was_held,
                          NormalSystem* sys) const {
  const double k_start = start_scale_;
  const bool free_rows = o_.unknowns == LinearUnknowns::kFreeRows;
  const bool log_priors = free_rows && linearize_at != nullptr;
  const double lambda = free_rows ? std::max(o_.prior_weight, 1e-14) : 1e-14;
  for (int j = 0; j < num_unknowns_; ++j) {
    if (j == lz_index_) continue;
    if (log_priors && !was_held[j]) {
      const double xc = linearize_at->values[j], offset = std::log(xc / initial_[j]);
      sys->triplets.emplace_back(j, j, lambda / (xc * xc));
      sys->rhs[j] += lambda * (1.0 - offset) / xc;
      continue;
    }
    const double least = pull_floor_.empty() ? 0.0 : pull_floor_[j];
    const double centre = log_priors ? linearize_at->values[j] : std::max(k_start * initial_[j], least);
    const double weight = log_priors ? 1e-14 : lambda;  // held: only keep the entry defined
    sys->triplets.emplace_back(j, j, weight / (centre * centre));
    sys->rhs[j] += weight / centre;
  }
}

void LinearSky::AddSmoothness(const LinearSkySolution* linearize_at, const std::vector<char>& was_held,
                              NormalSystem* sys) const {
  const bool log_priors = linearize_at != nullptr;  // free rows only
  const auto& grid = state_.preset.luts.grid;
  const double sqrt_s = std::sqrt(o_.smoothness);
  for (int t = 0; t < state_.tables; ++t)
    for (int row = 1; row + 1 < grid.n_theta; ++row) {
      if (!o_.row_fitted[row - 1] || !o_.row_fitted[row] || !o_.row_fitted[row + 1]) continue;
      for (int col = 0; col < grid.n_gamma; ++col)
        for (int c = 0; c < 3; ++c) {
          const int ub = ((t * grid.n_theta + row) * grid.n_gamma + col) * 3 + c;
          const int stride = grid.n_gamma * 3;
          const int idx[3] = {ub - stride, ub, ub + stride};
          if (was_held[idx[0]] || was_held[idx[1]] || was_held[idx[2]]) continue;
          const double second[3] = {1.0, -2.0, 1.0};
          double coef[3], target = 0.0;
          for (int i = 0; i < 3; ++i) {
            // Relative form x / x0 (scale-free) for the first solve; the log form,
            // linearised at xc, in Gauss-Newton steps.
            const double xc = log_priors ? linearize_at->values[idx[i]] : initial_[idx[i]];
            coef[i] = sqrt_s * second[i] / xc;
            if (log_priors) target -= sqrt_s * second[i] * (std::log(xc / initial_[idx[i]]) - 1.0);
          }
          for (int i = 0; i < 3; ++i) {
            sys->rhs[idx[i]] += target * coef[i];
            for (int j = 0; j < 3; ++j) sys->triplets.emplace_back(idx[i], idx[j], coef[i] * coef[j]);
          }
        }
    }
}

void LinearSky::DampTowardStart(NormalSystem* sys) const {
  // Toward the start's shape k x0, not toward zero: a weakly seen entry (a LUT column
  // only the lowest image row touches, with bilinear weight 0.1) keeps the start's
  // shape instead of shrinking (measured: such columns at 3-7% of the truth when
  // damped toward zero).
  const double k_start = start_scale_;
  const double mu = o_.unknowns == LinearUnknowns::kFreeRows ? 0.0 : o_.damping;
  for (int j = 0; j < num_unknowns_; ++j) {
    if (j == lz_index_) continue;
    const double added = mu * sys->normal.coeff(j, j);
    sys->normal.coeffRef(j, j) += added;
    sys->rhs[j] += added * k_start * initial_[j];
  }
}

void LinearSky::SolveActiveSet(const NormalSystem& eq, LinearSkySolution* sol) const {
  const Eigen::SparseMatrix<double>& normal = eq.normal;
  const Eigen::VectorXd& rhs = eq.rhs;
  std::vector<char> held(num_unknowns_, 0);
  Eigen::VectorXd x;
  // The rounds change only the diagonal: the fill-reducing ordering is computed once (the
  // day's first joint step takes 5 rounds).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool analysed = false;
  for (int round = 0; round < kActiveSetRounds; ++round) {
    Eigen::SparseMatrix<double> sys = normal;
    Eigen::VectorXd rb = rhs;
    for (int j = 0; j < num_unknowns_; ++j) {
      if (!held[j]) continue;
      // A hold much stiffer than the entry's own data: penalty x its diagonal.
      const double stiffness = kActiveSetPenalty * std::max(normal.coeff(j, j), 1e-300);
      sys.coeffRef(j, j) += stiffness;
      rb[j] += stiffness * Floor(j);
    }
    // Symmetric Jacobi scaling D N D (D = diag(N)^-1/2): LUT entries span orders of
    // magnitude between tables and columns, and the unpivoted sparse LDLT loses digits on
    // the unscaled matrix (measured: fits 10x off their ceiling at ridge 1e-14).
    Eigen::VectorXd d(num_unknowns_);
    for (int j = 0; j < num_unknowns_; ++j) d[j] = 1.0 / std::sqrt(std::max(sys.coeff(j, j), 1e-300));
    const Eigen::SparseMatrix<double> scaled = d.asDiagonal() * sys * d.asDiagonal();
    if (!analysed) {
      ldlt.analyzePattern(scaled);
      analysed = true;
    }
    ldlt.factorize(scaled);
    if (ldlt.info() != Eigen::Success) throw Error("linear sky solve: the normal equations are not positive definite");
    x = d.asDiagonal() * ldlt.solve(d.asDiagonal() * rb);
    // Hold entries that went below their floor; release held entries the objective
    // wants to raise (gradient of 1/2 x'Nx - b'x negative there: the KKT condition of a
    // lower bound fails), as in Lawson and Hanson's active-set NNLS.
    bool changed = false;
    const Eigen::VectorXd gradient = normal * x - rhs;
    for (int j = 0; j < num_unknowns_; ++j) {
      if (!held[j] && !(x[j] > Floor(j))) {
        held[j] = 1;
        changed = true;
      } else if (held[j] && gradient[j] * initial_[j] < -1e-12 * std::abs(rhs[j] * initial_[j]) - 1e-300) {
        held[j] = 0;
        changed = true;
      }
    }
    if (!changed) break;
  }
  sol->held = held;
  sol->values.resize(num_unknowns_);
  for (int j = 0; j < num_unknowns_; ++j) {
    sol->values[j] = std::max(x[j], Floor(j));
    sol->held_non_positive += held[j];
  }
}

void LinearSky::AddDataCost(const SolveInputs& in, LinearSkySolution* sol) const {
  // Cost and relative error of the data terms.
  double cost = 0.0, sq = 0.0, wsum = 0.0;
  size_t pixel_index = 0;
  for (const Row& row : rows_) {
    const RowValues v = Blend(row, *sol);
    for (size_t p = 0; p < row.pixels.size(); ++p) {
      const Pixel& px = row.pixels[p];
      for (int c = 0; c < 3; ++c) {
        const size_t smp = row.first_sample + 3 * p + c;
        const double e = (in.exposures[row.ref] * Model(row, px, c, in.phase_m[pixel_index + p], v) - px.ref[c]) / px.ref[c];
        const double rw = in.robust_weights.empty() ? 1.0 : in.robust_weights[smp];
        cost += 0.5 * rw * error_weight_[smp] * e * e;
        sq += error_weight_[smp] * e * e;
        wsum += error_weight_[smp];
      }
    }
    pixel_index += row.pixels.size();
  }
  sol->cost = cost;
  sol->rel_rmse = wsum > 0.0 ? std::sqrt(sq / wsum) : 0.0;
}

LinearSkySolution LinearSky::FromState(const FitState& state) const {
  LinearSkySolution s;
  s.g = state.g;
  s.values.assign(num_unknowns_, 0.0);
  s.held.assign(num_unknowns_, 0);
  if (o_.unknowns != LinearUnknowns::kFreeRows) throw Error("LinearSky::FromState: free rows only");
  const size_t table_size = state.preset.luts.table_size();
  for (int t = 0; t < state.tables; ++t)
    for (size_t i = 0; i < table_size; ++i) s.values[t * table_size + i] = std::exp(state.log_lut[t * table_size + i]);
  if (lz_index_ >= 0) s.values[lz_index_] = std::exp(state.log_overcast_zenith);
  s.overcast_zenith = std::exp(state.log_overcast_zenith);
  for (int j = 0; j < num_unknowns_; ++j) s.held[j] = j != lz_index_ && !(s.values[j] > Floor(j));
  return s;
}

size_t LinearSky::SampleReference(size_t sample) const {
  const auto it = std::upper_bound(rows_.begin(), rows_.end(), sample,
                                   [](size_t v, const Row& row) { return v < row.first_sample; });
  return std::prev(it)->ref;
}

std::vector<std::pair<int, int>> LinearSky::ObservedColumns() const {
  std::vector<std::pair<int, int>> out;
  for (const Row& row : rows_)
    for (const Row::Node& n : row.nodes) out.emplace_back(n.table, n.col);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

double LinearSky::MaxRelativeDifference(const LinearSkySolution& s, const std::vector<double>& exposures,
                                        const std::vector<ImageRGB>& images) const {
  const std::vector<double> values = ModelValues(s, exposures);
  double worst = 0.0;
  for (const Row& row : rows_)
    for (size_t p = 0; p < row.pixels.size(); ++p)
      for (int c = 0; c < 3; ++c) {
        const double predicted = values[row.first_sample + 3 * p + c];
        const double rendered = exposures[row.ref] * images[row.ref].at(row.pixels[p].x, row.y, c);
        worst = std::max(worst, std::abs(rendered - predicted) / std::max(std::abs(predicted), 1e-30));
      }
  return worst;
}

double LinearSky::RobustLogCost(const LinearSkySolution& s, const std::vector<double>& exposures, RobustLoss loss,
                                const std::vector<double>& scales) const {
  return RobustCostOf(LogErrors(s, exposures), loss, scales);
}

double LinearSky::RobustCostOf(const std::vector<double>& e, RobustLoss loss, const std::vector<double>& scales) const {
  double cost = 0.0;
  for (size_t i = 0; i < e.size(); ++i) {
    const double scale = scales[i];
    double rho = 0.0, drho = 1.0;
    RobustRho(loss, (e[i] / scale) * (e[i] / scale), &rho, &drho);
    cost += 0.5 * error_weight_[i] * scale * scale * rho;
  }
  return cost;
}

std::vector<double> LinearSky::ModelValues(const LinearSkySolution& s, const std::vector<double>& exposures) const {
  const std::shared_ptr<const std::vector<double>> phases = MiePhases(s.g);
  const std::vector<double>& phase_m = *phases;
  std::vector<double> out(error_weight_.size(), 0.0);
  size_t pixel_index = 0;
  for (const Row& row : rows_) {
    const RowValues v = Blend(row, s);
    for (size_t p = 0; p < row.pixels.size(); ++p)
      for (int c = 0; c < 3; ++c)
        out[row.first_sample + 3 * p + c] = exposures[row.ref] * Model(row, row.pixels[p], c, phase_m[pixel_index + p], v);
    pixel_index += row.pixels.size();
  }
  return out;
}

std::vector<double> LinearSky::LogErrors(const LinearSkySolution& s, const std::vector<double>& exposures) const {
  const std::shared_ptr<const std::vector<double>> phases = MiePhases(s.g);
  const std::vector<double>& phase_m = *phases;
  std::vector<double> out(error_weight_.size(), 0.0);
  size_t pixel_index = 0;
  for (const Row& row : rows_) {
    const RowValues v = Blend(row, s);
    for (size_t p = 0; p < row.pixels.size(); ++p) {
      const Pixel& px = row.pixels[p];
      for (int c = 0; c < 3; ++c) {
        const double mv = exposures[row.ref] * Model(row, px, c, phase_m[pixel_index + p], v);
        out[row.first_sample + 3 * p + c] = mv > 0.0 ? std::clamp(std::log(mv / px.ref[c]), -20.0, 20.0) : 20.0;
      }
    }
    pixel_index += row.pixels.size();
  }
  return out;
}

std::vector<double> LinearSky::BestExposures(const LinearSkySolution& s, const std::vector<double>& robust_weights) const {
  const std::shared_ptr<const std::vector<double>> phase_m = MiePhases(s.g);
  std::vector<double> num(n_refs_, 0.0), den(n_refs_, 0.0);
  for (const Row& row : rows_) {
    const size_t pixel_index = row.first_sample / 3;
    const RowValues v = Blend(row, s);
    for (size_t p = 0; p < row.pixels.size(); ++p) {
      const Pixel& px = row.pixels[p];
      for (int c = 0; c < 3; ++c) {
        const size_t smp = row.first_sample + 3 * p + c;
        const double w = error_weight_[smp] * (robust_weights.empty() ? 1.0 : robust_weights[smp]);
        const double q = Model(row, px, c, (*phase_m)[pixel_index + p], v) / px.ref[c];
        num[row.ref] += w * q;
        den[row.ref] += w * q * q;
      }
    }
  }
  std::vector<double> out(n_refs_, 1.0);
  for (int r = 0; r < n_refs_; ++r) {
    if (den[r] > 0.0 && num[r] > 0.0) out[r] = num[r] / den[r];
  }
  return out;
}

std::vector<double*> LinearSky::HeldParameters(const LinearSkySolution& s, FitState* state) const {
  std::vector<double*> out;
  const auto& grid = state->preset.luts.grid;
  for (int u = 0; u < num_unknowns_; ++u) {
    if (!s.held[u] || u == lz_index_) continue;
    const int c = u % 3;
    if (o_.unknowns == LinearUnknowns::kTiedRows) {
      const int col = (u / 3) % grid.n_gamma, t = u / (3 * grid.n_gamma);
      out.push_back(&state->log_delta[state->DeltaIndex(t, col, c)]);
    } else if (o_.unknowns == LinearUnknowns::kFreeRows) {
      const int col = (u / 3) % grid.n_gamma, row = (u / (3 * grid.n_gamma)) % grid.n_theta;
      const int t = u / (3 * grid.n_gamma * grid.n_theta);
      if (o_.row_fitted[row]) out.push_back(&state->log_lut[state->Index(t, row, col, c)]);
    }
  }
  return out;
}

void LinearSky::Apply(const LinearSkySolution& s, FitState* state) const {
  const auto& grid = state->preset.luts.grid;
  if (o_.unknowns == LinearUnknowns::kPerImageRow) throw Error("LinearSky: per-row solutions are not LUTs");
  for (int t = 0; t < state->tables; ++t)
    for (int col = 0; col < grid.n_gamma; ++col)
      for (int c = 0; c < 3; ++c) {
        if (o_.unknowns == LinearUnknowns::kTiedRows) {
          const int u = (t * grid.n_gamma + col) * 3 + c;
          state->log_delta[state->DeltaIndex(t, col, c)] = std::log(s.values[u]) - std::log(initial_[u]);
          continue;
        }
        for (int row = 0; row < grid.n_theta; ++row) {
          if (!o_.row_fitted[row]) continue;
          const int u = ((t * grid.n_theta + row) * grid.n_gamma + col) * 3 + c;
          state->log_lut[state->Index(t, row, col, c)] = std::log(s.values[u]);
        }
      }
  if (lz_index_ >= 0) state->log_overcast_zenith = std::log(std::max(s.overcast_zenith, 1e-6));
}

}  // namespace skycal::fit
