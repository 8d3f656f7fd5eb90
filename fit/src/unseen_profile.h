// The unseen-profile prior (linear_sky_unseen.cc) in the state's own parameters, for the Ceres
// polish (unseen_profile_term.h): what the linear start drew where no pixel looks, the polish
// keeps. Ceres-free: LinearSky fills it.
#pragma once
#include <array>
#include <vector>

namespace skycal::fit {

// One (column triple, sector, channel) term: per column i, the radiance the game draws there
// L_i = sum_n a_n exp(p_n) over the LUT parameters p_n (log_delta or log_lut) and the start's
// ln L0_i; the residuals sum_i s_i (ln L_i - ln L0_i) with s = second (the straight line) and
// s = first (the flat pull), both with their square-root weights in.
struct UnseenProfileResidual {
  struct Node {
    double* parameter;  // into FitState::log_delta (tied rows) or log_lut (free rows)
    double a;           // phase x bilinear weight x (tied: the start's blend; free: 1)
  };
  std::array<std::vector<Node>, 3> nodes;
  std::array<double, 3> log_l0{};
  std::array<double, 3> second{}, first{};
};

}  // namespace skycal::fit
