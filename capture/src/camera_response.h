// Camera response curves for the merge (internal to skycal_capture): analytic ones and
// recovery from brackets with OpenCV's photo module.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/hdr_merge.h"

namespace skycal::capture::detail {

// A bracket's code at buffer index i on the 8-bit scale (16-bit codes rounded).
inline uint8_t Code8(const BracketImage& img, size_t i) {
  const unsigned v = img.rgb[i];
  return static_cast<uint8_t>(img.bits == 16 ? std::min(255u, (v + 128u) / 257u) : std::min(255u, v));
}

// Well-exposedness weights per code (MergeOptions::weight); with `thresholded`, 0 at or
// below low_code and at or above high_code, > 0 strictly between (the "well exposed" codes).
struct WeightTable {
  std::vector<float> w;
  int low_code = 0;   // codes <= low_code are black
  int high_code = 0;  // codes >= high_code are clipped
};
WeightTable MakeWeights(const MergeOptions& options, int max_code, bool thresholded = true);

// kLinear / kSrgb: linear value per code, `levels` codes, R G B interleaved (levels * 3).
std::vector<float> AnalyticResponse(ResponseModel model, int levels);

// kDebevec / kRobertson on 8-bit codes (16-bit brackets are rounded to 8 bits for this):
// 256 * 3 values, normalised (NormaliseResponse). `images` sorted by exposure, ascending;
// `relative_exposure[i]` = k_i / k_max. Fills report["calibration"]. Unless
// options.opencv_calibration, only well-exposed samples enter the fit and the curve beyond
// the well-exposed codes is extrapolated (log-linear), so the top code's value, which fixes
// the normalisation, is an extrapolation rather than an average over clipped samples.
// shared_curve (kDebevec, skycal's solver): one curve fitted to the three channels' samples
// together and used for all three (kAuto when the channels' curves have one shape).
std::vector<float> RecoverResponse(const std::vector<const BracketImage*>& images,
                                   const std::vector<double>& relative_exposure, const MergeOptions& options,
                                   nlohmann::json* report, bool shared_curve = false);

// Adds samples' equations a(z) [g(z_pj) - ln E_p - ln k_j]^2 (codes[p * n + j], weight a per
// code, 0 = unused) to the normal equations of the 256 g's, each ln E_p eliminated in closed
// form (Schur complement), so the system stays 256 x 256 whatever the sample count. H: 256 x
// 256 doubles (symmetric, so either storage order), rhs: 256.
void AddSamplesEliminatingLnE(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& ln_k,
                              const std::vector<double>& a, double* H, double* rhs);

// ResponseModel::kWeighted for channel c (weighted_response.cc): g(z) = ln f(z) per 8-bit
// code, up to a constant; ln_k per image (sorted as for RecoverResponse). Fills *report.
std::vector<double> RecoverWeightedLogResponse(const std::vector<const BracketImage*>& images,
                                               const std::vector<double>& ln_k, int c, const MergeOptions& options,
                                               nlohmann::json* report);

// Whether the brackets determine a recovered curve (response_determinacy.cc): per channel,
// the share of pixels well exposed (MergeOptions thresholds) in >= 2 brackets and the codes
// that pixels show but hardly any such pixel does (unlinked). Appends a warning (the channel,
// the codes, the reason) when the share is under 1% or >= max(5, 2% of the fit codes) codes
// are unlinked.
nlohmann::json ResponseDeterminacy(const std::vector<const BracketImage*>& images, const MergeOptions& options,
                                   std::vector<std::string>* warnings);

// kAuto's test of "one shape": the largest RMS over codes lo..hi, between two channels, of
// the difference of their ln f (g per channel, 256 codes) less its mean (the per-channel
// scale is a gauge), natural log units.
double ChannelShapeDifference(const std::array<std::vector<double>, 3>& g, int lo, int hi);

// Fills non-finite entries from their neighbours, clamps negatives to 0 and scales each
// channel so the top code is 1. Returns the number of decreasing steps (all channels).
int NormaliseResponse(std::vector<float>* curve, int levels);

// A 256-level curve resampled to 65536 codes (code / 257, linear interpolation).
std::vector<float> ExpandResponse(const std::vector<float>& curve256);

}  // namespace skycal::capture::detail
