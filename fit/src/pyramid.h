// Area-averaged levels of a reference for coarse-to-fine fitting. A level is itself a
// lat-long in the project's convention (so the renderer can draw the model at the same
// nodes): each fine pixel is assigned to the nearest coarse node in latitude and
// longitude, and the coarse value is the solid-angle-weighted mean of its fitted (kSky)
// fine pixels. Averaging in linear radiance, before the log, keeps the mean unbiased.
#pragma once
#include <vector>

#include "skycal/fit/reference.h"

namespace skycal::fit {

struct FitLevel {
  int width = 0, height = 0;
  std::vector<float> radiance;  // 3 per pixel, linear mean (0 where weight is 0)
  std::vector<double> weight;   // per pixel: fitted solid angle (sr); 0 = not fitted
  double total_weight = 0.0;
};

// `width` must be even and at most the reference's width; height = width / 2 (a reference
// with horizon-biased rows is read at each node row's elevation through the mapping's
// exact inverse, then binned in longitude like any other). A coarse
// pixel is fitted when at least half of the solid angle assigned to it is fitted.
FitLevel BuildLevel(const Reference& ref, int width);

// Automatic coarse-to-fine widths: 64, 128, ... up to min(reference width, 512).
std::vector<int> AutomaticPyramid(int reference_width);

}  // namespace skycal::fit
