// The pieces the entry points share: choosing the cloud pixels and their samples, the
// conditioning at a point, the cloud block's bounds and held entries in a Ceres problem,
// a solve of the cloud block alone, and the report.
#pragma once
#include <ceres/ceres.h>

#include <functional>
#include <string>
#include <vector>

#include "cloud_lighting_conditioning.h"
#include "cloud_lighting_samples.h"
#include "skycal/cloudfit/cloud_lighting_fit.h"

namespace skycal::cloudfit {

// The cloud render of a frame of the reference's size with the known shapes' wind time
// and march.
clouds::CloudRenderRequest RequestFor(const std::array<double, 3>& sun_dir, int width, int height,
                                      const KnownCloudShapes& shapes);

// Cloud pixels: `usable` (per pixel) and transmittance below the threshold.
std::vector<size_t> CloudPixels(const std::vector<char>& usable, const std::vector<float>& transmittance,
                                double threshold);
// Up to `count` of them spread evenly through the list (row-major: every region of the
// cloud field is represented), weighted by solid angle (weights sum to 1).
std::vector<CloudSample> ChooseSamples(const std::vector<size_t>& pixels, const ImageRGB& reference, int count);

// The conditioning at theta (one Jacobian evaluation, unweighted rows).
Conditioning ConditionAt(CloudSampleModel* model, const CloudLighting& theta, const CloudLightingOptions& o);

// Adds the cloud block (bounds from the spec table; held entries constant) to `problem`.
void AddCloudBlock(ceres::Problem* problem, CloudSampleModel* model, double* theta, const Conditioning& c);

// A free parameter the solve left at an end of its range may sit in a basin its bound made
// (the fit ran there and stopped): each such parameter of `*theta` is solved again by `solve`
// (which moves the lighting it is given and returns its final cost) from `start` with that
// parameter a quarter of its range in from the other end, and the lowest cost is kept in
// `*theta` and `*cost`. On a photo's recovered shapes the multiple-scattering factor ended at
// 1 or at 0 for shapes that differed by one refinement render, the 0 a far better image
// (bench/results/weather_inversion.md). Returns how many restarts ran and which was kept.
struct BoundRestarts {
  int tried = 0;
  int kept = -1;          // index of the restart kept; -1: the first solve stood
  std::string parameter;  // the kept restart's parameter
};
BoundRestarts RestartAtBounds(const CloudLighting& start, const std::vector<char>& held,
                              const std::function<double(CloudLighting*)>& solve, CloudLighting* theta, double* cost);

// CloudLightingOptions::release_inseparable: the parameters `*c` holds as inseparable are freed
// and `solve` (given the freed conditioning; it moves the lighting and returns its final cost)
// continues from `*theta`. Kept when its cost is below `*cost`: `*theta`, `*cost` and `*c`
// (those parameters no longer held, their why saying so) updated. No solve when nothing is
// held as inseparable.
struct ReleasedHolds {
  std::vector<std::string> names;  // the parameters freed, CloudLightingNames order
  bool kept = false;
  double cost_before = 0.0, cost_after = 0.0;
};
ReleasedHolds ReleaseInseparableHolds(const std::function<double(const Conditioning&, CloudLighting*)>& solve,
                                      Conditioning* c, CloudLighting* theta, double* cost);

// Solves the cloud block alone (the sky fixed); returns the Ceres summary. `start`: the
// centre of CloudLightingOptions::start_prior.
ceres::Solver::Summary SolveCloudBlock(CloudSampleModel* model, double* theta, const Conditioning& c,
                                       const CloudLightingOptions& o, const CloudLighting& start);

// A day's cloud blocks in one problem: one block per reference (models[r], thetas[r]; the
// sky fixed), the held entries of `c` held in every block, and with three or more
// references and o.day_smoothness > 0 the time-of-day prior (cloud_lighting_day_prior.h)
// over each reference and its neighbours in time. `times_h`: one per reference, distinct;
// `scale`: the prior's unit per parameter. With one reference and o.start_prior > 0, the pull
// toward `start` (non-null) too; `prior_residuals` counts the day's prior only.
ceres::Solver::Summary SolveCloudDay(const std::vector<CloudSampleModel*>& models, const std::vector<double*>& thetas,
                                     const Conditioning& c, const std::vector<double>& times_h,
                                     const CloudLighting& scale, const CloudLightingOptions& o, int* prior_residuals,
                                     const CloudLighting* start);

// Errors of a composite against the reference at `pixels` (solid-angle weighted).
PixelErrors CompositeErrors(const std::vector<size_t>& pixels, const ImageRGB& reference, const ImageRGB& composite);
// sky_exposed x T + exposure x L_cloud (the sky already multiplied by the exposure).
ImageRGB Composite(const ImageRGB& sky_exposed, const clouds::CloudImage& cloud, double exposure);

// Fills the parameter table and conditioning of `report`.
void ReportParameters(const CloudLighting& initial, const CloudLighting& final_theta, const Conditioning& c,
                      CloudLightingReport* report);

}  // namespace skycal::cloudfit
