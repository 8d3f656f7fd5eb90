// The sky model's linear structure, used directly (variable projection).
//
// For a fixed haziness g the model of sky_model.glsl.h is linear in every LUT entry and in
// the overcast zenith luminance L_z: at a pixel of a level image, channel c,
//   M = (1 - w_o) sum_t sum_(row, col) wr(row) wc(col) LUT_t(row, col, c) phase_t(mu)
//       + w_o L_z (1 + 2 sin(elevation)) / 3,
// with wr / wc the bilinear weights of lut_row / lut_col and phase_t the Rayleigh,
// Cornette-Shanks (g) and isotropic phases, all taken from the shared model source. So the
// LUT that best fits a reference for a given g (and exposures) is a linear least-squares
// solve, and only g is searched (a 1-D problem). The error measure is the relative error
// (k M - R) / R, weighted by solid angle: its square is what fit::CompareToReference
// reports as rel_rmse, and to first order it is the log error the Ceres polish minimises.
//
// Unknowns, per channel (and L_z, grey, shared):
//  - tied rows (one reference, see sky_row_cost.h): V_t(col, c) = the LUT blended between
//    the two rows around the sun angle; the fit then sets both rows to exp(u0 + d) with
//    d = log(V / V0), V0 the same blend of the initial preset;
//  - free rows (several references): T_t(row, col, c) for every fitted row;
//  - per image row (the ceiling tool only): one value per (table, level row, channel), no
//    interpolation between LUT columns: what the model could do with an unlimited number
//    of LUT columns (the LUT's resolution cost, seen against the LUT ceiling).
// Regularisation: a damping of the normal equations (see LinearSkyOptions::damping), a
// 1e-14 pull toward the start's shape (only entries no pixel sees feel it) and, with free
// rows, the second difference of the change along the sun zenith (FitOptions::smoothness);
// tied or free, the rendered profile across the LUT columns at the azimuths no pixel reads
// (FitOptions::unseen_profile, linear_sky_unseen.cc). Entries the solve would make
// non-positive are held at 1e-6 of their initial value (an active set, formed anew in every
// solve).
#pragma once
#include <array>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "fit_state.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_options.h"
#include "pyramid.h"
#include "unseen_profile.h"
#include "skycal/fit/reference.h"

namespace skycal::fit {

enum class LinearUnknowns { kTiedRows, kFreeRows, kPerImageRow };

struct LinearSkyOptions {
  LinearUnknowns unknowns = LinearUnknowns::kTiedRows;
  std::vector<bool> row_fitted;  // free rows: which LUT rows are unknowns (others held)
  bool fit_overcast = false;     // L_z is an unknown (needs overcast_weight > 0)
  // Use every stride-th pixel of every stride-th row of the level (1: all). A decimated
  // level keeps the exact pixel values and directions: an area-averaged coarser level
  // differs from the model at its node by the averaging, which biases g where g is weakly
  // determined (measured: a sun 4 deg below the horizon, g 0.40 instead of 0.80 from a
  // 128-wide average of a 256-wide reference; exact from every second pixel).
  int stride = 1;
  int threads = 2;               // for the normal equations' accumulation (1 or 2)
  // Damping of the data's normal equations, N_jj (1 + damping), toward the start's shape
  // rescaled to the data (k x0; Levenberg's damping, relative, so it is scale-free): holds the combinations a short image
  // row cannot tell apart (two tables' phases nearly collinear along it) and costs a
  // relative 1e-6 on the determined ones. Measured (fit_ceiling_test): 1e-4 held CIE
  // skies at 0.05% against a 0.005% ceiling; 1e-6 and 1e-8 agree to 1e-5 everywhere.
  double damping = 1e-6;         // tied and per-row unknowns only
  double prior_weight = 1e-8;    // free rows: the pull toward the start (FitOptions::prior_weight)
  double smoothness = 1e-6;      // as FitOptions::smoothness (free rows)
  // FitOptions::unseen_profile: the weight of the rendered profile's second difference across
  // the LUT columns at the azimuths no fitted pixel reads (and of its flat pull, times
  // linear_sky_unseen.cc's kUnseenSlope), tied or free rows (0: off).
  double unseen_profile = 0.0;
  // Per LUT column, per azimuth sector (kSectors of them), whether some fitted pixel reads
  // it: given (the finest level's, so that every level smooths the same azimuths), else
  // the level's own.
  std::vector<std::vector<char>> column_sectors;
};

// One solve's result, in the units of the model (cd/m^2 * sr for the LUT).
struct LinearSkySolution {
  double g = 0.0;
  double cost = 0.0;              // 1/2 sum of weighted squared relative errors (data only)
  double rel_rmse = 0.0;          // sqrt(sum w e^2 / sum w) over fitted pixels and channels
  std::vector<double> values;     // per unknown (layout: see LinearSky::Index*)
  double overcast_zenith = 0.0;   // L_z, cd/m^2
  int held_non_positive = 0;      // entries held at their floor by the active set
  std::vector<char> held;         // per unknown: held at its floor
};

class LinearSky {
 public:
  // levels[r] is the level image of refs[r] (all the same size); the state gives the grid,
  // the variant, w_o and the initial values (priors, floors, tied blends).
  LinearSky(const FitState& state, const std::vector<const FitLevel*>& levels, const std::vector<Reference>& refs,
            LinearSkyOptions options);

  // Solves for the LUT (and L_z) at haziness g with the given exposures (model -> image
  // factor per reference) and robust weights (per pixel and channel, LogErrors layout;
  // empty: all 1). Error measure: the relative error (k M - R) / R, or, with
  // `linearize_at`, one Gauss-Newton step of the log error ln(k M / R) linearised at that
  // solution's model values M0: ln(k M0 / R) + (M - M0) / M0 (the same linear unknowns,
  // rows scaled by 1 / M0 instead of 1 / R). Repeated, it converges to the log-space
  // optimum the Ceres polish would reach.
  // with_cost: fill `cost` and `rel_rmse` (one more pass over the samples; the
  // Gauss-Newton steps and the g search do without).
  LinearSkySolution Solve(double g, const std::vector<double>& exposures, const std::vector<double>& robust_weights,
                          const LinearSkySolution* linearize_at = nullptr, bool with_cost = true) const;
  // 1/2 sum w s^2 rho((e / s)^2) of the log errors: the robust cost of the Ceres problem's
  // sky rows (without priors), for comparing g values.
  double RobustLogCost(const LinearSkySolution& s, const std::vector<double>& exposures, RobustLoss loss,
                       const std::vector<double>& scales) const;  // scale per sample
  // The same from log errors already computed (LogErrors), without another pass.
  double RobustCostOf(const std::vector<double>& e, RobustLoss loss, const std::vector<double>& scales) const;
  // Angle between each sample's view direction and the sun, degrees (LogErrors layout).
  const std::vector<double>& sun_angles_deg() const { return sun_angle_deg_; }
  // Model values k M per pixel and channel (LogErrors layout), for the render check.
  std::vector<double> ModelValues(const LinearSkySolution& s, const std::vector<double>& exposures) const;

  // Log errors ln(k M / R) of a solution, per pixel and channel (a non-positive model
  // value gives +-20, far outside any loss scale).
  std::vector<double> LogErrors(const LinearSkySolution& s, const std::vector<double>& exposures) const;
  // Solid-angle weights matching LogErrors (w / total, summing to 1 per channel).
  const std::vector<double>& error_weights() const { return error_weight_; }
  // Least-squares exposure factor of each reference for a solution (relative error; each
  // on its own pixels), in one pass over the samples.
  std::vector<double> BestExposures(const LinearSkySolution& s, const std::vector<double>& robust_weights) const;

  // Writes a tied-rows or free-rows solution into the state (log_delta or log_lut, and
  // log L_z when it was fitted).
  void Apply(const LinearSkySolution& s, FitState* state) const;

  // The state's parameters (log_delta or log_lut entries) of the unknowns a solution held
  // at their floor: the data want them <= 0, so the log-space polish holds them too (a
  // log parameter chasing zero only slows Levenberg-Marquardt down).
  std::vector<double*> HeldParameters(const LinearSkySolution& s, FitState* state) const;

  // Free rows: the state's LUT (and L_z) as a solution to linearise at (g = state.g).
  LinearSkySolution FromState(const FitState& state) const;
  // The reference a sample (LogErrors layout) belongs to.
  size_t SampleReference(size_t sample) const;
  // (table, LUT column) pairs some fitted pixel reads (-1 column: per-image-row unknowns).
  std::vector<std::pair<int, int>> ObservedColumns() const;
  // Largest relative difference between the solution's model values and `images` (one
  // per reference, level size, without exposure), over the fitted pixels: the check that
  // the renderer computes what the linear structure predicted.
  double MaxRelativeDifference(const LinearSkySolution& s, const std::vector<double>& exposures,
                               const std::vector<ImageRGB>& images) const;

  int num_unknowns() const { return num_unknowns_; }
  // Tied rows: per LUT column and azimuth sector, whether some fitted pixel reads it.
  static constexpr int kSectors = 36;  // 10 degrees of azimuth each
  const std::vector<std::vector<char>>& column_sectors() const { return column_sectors_; }
  // LUT columns read at some sectors but not all; the unseen-profile terms built for them.
  int partly_seen_columns() const;
  int unseen_profile_terms() const { return static_cast<int>(profile_terms_.size()); }
  // The same terms on the state's parameters (log_delta or log_lut), the Mie phase at the
  // state's g: the Ceres polish's residuals (unseen_profile_term.h).
  std::vector<UnseenProfileResidual> UnseenProfileResiduals(FitState* state) const;
  int width() const { return width_; }  // of the level it was built on
  size_t num_samples() const { return error_weight_.size(); }

 private:
  struct Pixel {
    int x;                    // column in the level image
    double sqrt_weight;       // sqrt(solid angle / total)
    double mu, one_minus_mu;  // cos(view, sun) and 1 - it (the shared source's form)
    double phase_r;           // Rayleigh phase (independent of g)
    std::array<double, 3> ref;
  };
  // One level row of one reference: its pixels, and per (table, k) the unknown and the
  // bilinear weight it enters with (k runs over the 1, 2 or 4 (row, col) nodes).
  struct Row {
    size_t ref;
    int y;                    // row in the level image
    double overcast_shape;    // (1 + 2 sin(elevation)) / 3
    std::vector<Pixel> pixels;
    size_t first_sample;      // index of its first (pixel, channel) in the samples layout
    struct Node { int table; int col; int unknown_ch0; double weight; };  // unknown of channel c: unknown_ch0 + c
    std::vector<Node> nodes;
  };
  // A solution's values along one row: per channel and table the LUT blended over the
  // row's nodes (the bilinear weights are the row's), and L_z. The model at a pixel is then
  // (1 - w_o) sum_t phase_t lut[c][t] + w_o lz shape: three products instead of a pass
  // over the row's up to 12 nodes.
  struct RowValues {
    double lut[3][3] = {};  // [channel][table]
    double lz = 0.0;
  };
  RowValues Blend(const Row& row, const LinearSkySolution& s) const;
  // M / exposure at a pixel for channel ch, given the Mie phase there.
  double Model(const Row& row, const Pixel& px, int ch, double phase_m, const RowValues& v) const;
  // Per pixel, rows in order; the last g's are kept (a day's joint steps and a search's
  // repeated solves at one g compute them once).
  std::shared_ptr<const std::vector<double>> MiePhases(double g) const;
  double Floor(int j) const;                      // value non-positive entries are held at
  // Least-squares scale of the start (initial values) on the data, at the start's g and
  // exposures: the centre of the prior is this scale times the start (see Solve).
  double StartScale(const std::vector<double>& exposures, const std::vector<double>& phase_m) const;
  // One reference: per unknown a pixel reads of a Rayleigh or Mie table the start makes
  // vanishing at the reference's sun (FitState::kVanishingTable), kPullFloorShare of the
  // other table's largest entry in its channel times the start scale; 0 for the others.
  std::vector<double> PullFloor(const Reference& ref) const;

  // Construction, per reference and level row (the constructor's stages).
  double InitialLut(int t, int row, int col, int ch) const;  // exp of the start's log LUT
  void AddReferenceRows(size_t r, const FitLevel& lv, const Reference& ref, double total_weight, size_t* sample);
  void AddRowPixels(Row* row, const FitLevel& lv, const Reference& ref, double total_weight, size_t* sample);
  // The row's (table, node) unknowns and bilinear weights (wr around LUT row row0, wc
  // around column col0), and the start values of the unknowns they blend.
  void AddRowNodes(Row* row, int h, int row0, const double wr[2], int col0, const double wc[2]);

  // Solve's stages (types in linear_sky.cc, keeping Eigen out of this header): the data's
  // normal equations, the priors and smoothness, the damping, the active-set solve and
  // the data cost.
  struct NormalSystem;
  struct SolveInputs;
  struct FeatureMoments;
  NormalSystem AccumulateData(const SolveInputs& in) const;
  void AccumulateRows(size_t row_begin, size_t row_end, const SolveInputs& in, NormalSystem* part) const;
  void AccumulateRow(const Row& row, const SolveInputs& in, NormalSystem* part) const;
  FeatureMoments ChannelMoments(const Row& row, int c, const SolveInputs& in, const RowValues& v0) const;
  void AddPriors(const LinearSkySolution* linearize_at, const std::vector<char>& was_held, NormalSystem* sys) const;
  void AddSmoothness(const LinearSkySolution* linearize_at, const std::vector<char>& was_held,
                     NormalSystem* sys) const;
  void DampTowardStart(NormalSystem* sys) const;
  // The rendered profile at the unseen azimuths (linear_sky_unseen.cc): which sectors each
  // column is read in, the (column triple, sector) terms, and their rows in the normal
  // equations at haziness g.
  std::vector<std::vector<char>> ColumnSectors(size_t ref) const;
  void BuildProfileTerms(const std::vector<Reference>& refs);
  void AddProfileTerms(const std::vector<std::vector<char>>& sectors, const Reference& ref);
  void AddUnseenProfile(double g, const LinearSkySolution* linearize_at, NormalSystem* sys) const;
  struct ProfileTerm;
  // The normal equations of consecutive residuals on the same unknowns, summed densely.
  struct ProfileBlock {
    static constexpr int kMax = 18;  // 3 columns x 3 tables x 2 rows
    int n = 0;
    std::array<int, kMax> index{};
    std::array<double, kMax * kMax> normal{};
    std::array<double, kMax> rhs{};
    void Flush(NormalSystem* sys);  // into the system's triplets and rhs; empties the block
  };
  // One residual of a term for channel c: sum_i s[i] ln(L_i / L0_i), `phase` the tables'
  // phases at each column's direction; into `block`, flushed first when its unknowns differ.
  void AddProfileResidual(const ProfileTerm& t, const std::array<std::array<double, 3>, 3>& phase, int c,
                          const std::array<double, 3>& s, const LinearSkySolution* linearize_at,
                          ProfileBlock* block, NormalSystem* sys) const;
  void SolveActiveSet(const NormalSystem& eq, LinearSkySolution* sol) const;  // values, held
  void AddDataCost(const SolveInputs& in, LinearSkySolution* sol) const;       // cost, rel_rmse

  const FitState& state_;
  LinearSkyOptions o_;
  std::vector<Row> rows_;
  std::vector<double> error_weight_;   // per sample
  std::vector<double> sun_angle_deg_;  // per sample
  std::vector<double> initial_;        // x0 per unknown (prior reference and floor)
  int num_unknowns_ = 0;
  int lz_index_ = -1;
  double held_overcast_zenith_ = 0.0;  // L_z when it is not an unknown, cd/m^2
  double start_scale_ = 1.0;           // StartScale at the state's g and exposures
  std::vector<double> pull_floor_;     // per unknown, the least centre of the pull toward the start (PullFloor)
  std::vector<std::vector<char>> column_sectors_;  // tied rows: ColumnSectors or the given
  // Three consecutive LUT columns one reference sees somewhere and not all round, at one
  // azimuth sector where it does not see all three: per column, the view direction's phase
  // terms at the column's node elevation, and the unknowns the game blends there (per table,
  // the tied value, or the two free rows around the reference's sun with their weights).
  struct ProfileTerm {
    struct Node {
      int table, unknown_ch0;
      double weight;
    };
    double mu[3], one_minus_mu[3], phase_r[3];
    std::array<std::array<Node, 6>, 3> nodes;  // at most 3 tables x 2 rows
    std::array<int, 3> n_nodes{};
  };
  std::vector<ProfileTerm> profile_terms_;
  int n_refs_ = 0;
  int width_ = 0;
  struct PhaseCache {
    std::mutex mutex;
    double g = 0.0;
    std::shared_ptr<const std::vector<double>> phases;
  };
  std::unique_ptr<PhaseCache> phase_cache_ = std::make_unique<PhaseCache>();
};

}  // namespace skycal::fit
