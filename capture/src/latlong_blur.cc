#include "latlong_blur.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace skycal::capture {

cv::Mat BlurWrapped(const cv::Mat& band, double sigma_px) {
  const int pad = std::min(band.cols, static_cast<int>(std::ceil(3.0 * sigma_px)) + 1);
  cv::Mat padded, blurred;
  cv::copyMakeBorder(band, padded, 0, 0, pad, pad, cv::BORDER_WRAP);
  cv::GaussianBlur(padded, blurred, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
  return blurred(cv::Rect(pad, 0, band.cols, band.rows)).clone();
}

}  // namespace skycal::capture
