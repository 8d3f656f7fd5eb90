// Image errors the suites share (private to skycal_bench).
#pragma once
#include "skycal/core/image.h"

namespace skycal::bench {

// Solid-angle weighted (core/latlong.h PixelSolidAngle) relative RMS error of `image` against `truth`, over
// truth pixels above `min_elevation_deg` whose three channels are finite and positive in
// both. `image` may be smaller: it is sampled bilinearly at the directions of the truth's
// pixel centres, as a game samples a low-resolution sky texture. With `fit_scale` the error
// is taken after the best single scale factor (the median of image/truth), for outputs
// whose absolute exposure is arbitrary. NaN when no pixel qualifies.
double RelRmse(const ImageRGB& truth, const ImageRGB& image, double min_elevation_deg, bool fit_scale = false);

// `fine` averaged onto the nodes of a width x height lat-long: each fine pixel goes to its
// nearest node (the seam's two columns are one direction), weighted by its solid angle, as
// the fit's pyramid levels are built (fit/src/pyramid.h). What a filtered output of that size
// should hold, so an output is compared with the scene at its own resolution rather than
// charged for the detail a coarser grid cannot carry. Nodes no fine pixel reaches: 0.
ImageRGB AreaMeanAtNodes(const ImageRGB& fine, int width, int height);

// True when every value is finite.
bool AllFinite(const ImageRGB& image);

}  // namespace skycal::bench
