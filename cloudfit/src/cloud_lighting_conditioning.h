// What the cloud pixels can tell apart. From the Jacobian of the log composite with respect
// to the lighting parameters (one row per sampled pixel and channel), per parameter: its
// sensitivity, the error a fit would have under a stated per-pixel noise (the covariance
// sigma^2 (J^T J)^-1 of least squares, in relative units), and its most collinear partner;
// the singular values of the column-normalised Jacobian. Parameters the data cannot
// determine to `max_relative_error` are held (greedily, the worst first, recomputing after
// each), so the fit never wanders along a direction the images do not see.
#pragma once
#include <string>
#include <vector>

#include "skycal/cloudfit/cloud_lighting_params.h"

namespace skycal::cloudfit {

struct ConditioningOptions {
  double noise = 0.02;               // per pixel and channel, relative (log units)
  double max_relative_error = 0.01;  // hold a parameter predicted worse than this
  double min_sensitivity = 1e-6;     // RMS d log(composite) / d log(theta) below: unobserved
  std::vector<bool> user_held;       // size kCloudLightingParameters, or empty
  std::vector<std::string> held_why; // per user-held parameter, its reason ("" or empty: on request)
  bool auto_hold = true;
};

struct ParameterConditioning {
  double scale = 0.0;                // the parameter's unit of relative change (|theta| or 1% of its range)
  double sensitivity = 0.0;          // RMS over rows of d log(composite) / (d theta / scale)
  double predicted_relative_error = 0.0;  // with every non-held parameter free; inf when unobservable
  double separability = 0.0;         // 1 / sqrt(VIF) among all observed parameters: 1 independent, 0 collinear
  int most_collinear = -1;           // the parameter whose column is closest in angle
  double collinear_cosine = 0.0;     // |cos| of that angle
  bool held = false;
  bool inseparable = false;          // held by the separability rule (not unobserved, not on request)
  std::string why;                   // when held; or why a hold was released (ReleaseInseparableHolds)
};

struct Conditioning {
  std::vector<ParameterConditioning> parameters;  // kCloudLightingParameters
  std::vector<double> singular_values;            // column-normalised, every observed parameter, descending
  std::vector<double> singular_values_free;       // the parameters left free
};

// `jacobian`: rows x kCloudLightingParameters, row-major, d log(composite) / d theta
// (unweighted: one row per pixel channel, each with noise `options.noise`).
Conditioning AnalyseConditioning(const std::vector<double>& jacobian, const CloudLighting& theta,
                                 const ConditioningOptions& options);

}  // namespace skycal::cloudfit
