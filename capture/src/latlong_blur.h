// Gaussian blur of a lat-long band (rows of one frame, all its columns) that wraps in
// longitude: cv::GaussianBlur has no wrap border, so both sides are padded by the kernel's
// reach, blurred, and cropped; the rows reflect at the band's ends. Capture's one place for
// the lat-long's seam (core/latlong.h) in image filtering.
#pragma once
#include <opencv2/core.hpp>

namespace skycal::capture {

cv::Mat BlurWrapped(const cv::Mat& band, double sigma_px);

}  // namespace skycal::capture
