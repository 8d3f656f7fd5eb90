// Compositing clouds over the sky: L = L_sky T + L_cloud per pixel and channel, the
// a separate step (docs/cloud-model.md, "Output"; with coverage 0, T = 1 and L_cloud = 0 exactly, so the
// composite equals the clear sky bit for bit).
#pragma once
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/image.h"

namespace skycal::clouds {

// Throws skycal::Error unless the images have the same size.
ImageRGB CompositeClouds(const ImageRGB& sky, const CloudImage& clouds);

}  // namespace skycal::clouds
