// cv::Mat <-> Raster in OpenCV's channel convention (what imencode/imread did): 3 channels
// are B, G, R and 4 are B, G, R, A in the Mat, R, G, B(, A) in the Raster and the PNG; 1 and
// 2 channels unchanged. Header-only: include it only where OpenCV is linked already.
#pragma once
#include <opencv2/core.hpp>

#include <cstring>
#include <string>

#include "skycal/core/error.h"
#include "skycal/core/png_io.h"

namespace skycal {

inline Raster RasterFromMat(const cv::Mat& m, const std::string& what) {
  const int bits = m.depth() == CV_8U ? 8 : (m.depth() == CV_16U ? 16 : 0);
  if (bits == 0 || m.channels() < 1 || m.channels() > 4) {
    throw Error(what + ": expected an 8- or 16-bit image of 1-4 channels for PNG");
  }
  Raster r(m.cols, m.rows, m.channels(), bits);
  const size_t sample = bits / 8;
  for (int y = 0; y < m.rows; ++y) {
    const uint8_t* src = m.ptr<uint8_t>(y);
    uint8_t* dst = r.row(y);
    if (r.channels < 3) {
      std::memcpy(dst, src, r.row_bytes());
      continue;
    }
    for (int x = 0; x < m.cols; ++x) {
      const size_t p = static_cast<size_t>(x) * r.channels * sample;
      std::memcpy(dst + p, src + p + 2 * sample, sample);  // R <- the Mat's third channel
      std::memcpy(dst + p + sample, src + p + sample, sample);
      std::memcpy(dst + p + 2 * sample, src + p, sample);   // B <- the first
      if (r.channels == 4) std::memcpy(dst + p + 3 * sample, src + p + 3 * sample, sample);
    }
  }
  return r;
}

inline std::vector<uint8_t> EncodePngFromMat(const cv::Mat& m, const std::string& what, int compression = 1) {
  return EncodePng(RasterFromMat(m, what), what, compression);
}

}  // namespace skycal
