// Minimal DNG files for the RAW reader's tests (capture/raw_decode.h), written with libtiff:
// uncompressed 16-bit LinearRaw (photometric 34892: three samples per pixel, no mosaic) or
// an RGGB Bayer CFA (photometric 32803), with the DNG tags LibRaw reads (DNGVersion,
// UniqueCameraModel, BlackLevel, WhiteLevel, ColorMatrix1 + CalibrationIlluminant1,
// AsShotNeutral, Orientation) and an EXIF directory (ExposureTime, FNumber,
// ISOSpeedRatings, FocalLength, LensModel). Test code only: the library writes no RAW.
#pragma once
#include <tiffio.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/core/image.h"

namespace skycal::testing {

// XYZ (D65) -> linear Rec.709 RGB (IEC 61966-2-1): a camera whose ColorMatrix1 is this
// sees Rec.709 RGB directly (its camera-to-Rec.709 matrix is the identity).
inline constexpr std::array<double, 9> kXyzToRec709 = {3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108,
                                                       0.0415560, 0.0556434,  -0.2040259, 1.0572252};

struct DngSpec {
  int width = 0, height = 0;
  bool cfa = false;                // false: LinearRaw RGB; true: RGGB Bayer mosaic
  std::vector<uint16_t> samples;   // raw values (black included): width*height*3 (RGB) or width*height (CFA)
  int black = 0, white = 65535;    // BlackLevel, WhiteLevel (raw units)
  std::array<double, 9> color_matrix1 = kXyzToRec709;  // XYZ -> camera, row-major (DNG ColorMatrix1)
  std::array<double, 3> as_shot_neutral = {1.0, 1.0, 1.0};
  double exposure_time_s = 1.0 / 125, f_number = 8.0, iso = 100.0, focal_length_mm = 8.0;
  std::string make = "Skycal", model = "Test Camera", lens = "Skycal Test Lens 8mm";
  int orientation = 1;             // TIFF Orientation (1: top-left)
  uint16_t compression = COMPRESSION_NONE;  // COMPRESSION_LZW: a DNG LibRaw does not decode
};

// Linear scene values (0..1 = black..white, clipped) -> raw values round(black + v * (white - black)).
inline uint16_t EncodeRaw(double v, int black, int white) {
  v = std::fmin(std::fmax(v, 0.0), 1.0);
  return static_cast<uint16_t>(std::lround(black + v * (white - black)));
}

namespace detail {
inline void Check(int ok, const std::string& path, const char* what) {
  if (!ok) throw Error(path + ": libtiff could not write " + what);
}

inline void SetDngTags(TIFF* tif, const DngSpec& s, const std::string& path) {
  const uint8_t version[4] = {1, 4, 0, 0};
  Check(TIFFSetField(tif, TIFFTAG_DNGVERSION, version), path, "DNGVersion");
  Check(TIFFSetField(tif, TIFFTAG_UNIQUECAMERAMODEL, (s.make + " " + s.model).c_str()), path, "UniqueCameraModel");
  Check(TIFFSetField(tif, TIFFTAG_MAKE, s.make.c_str()), path, "Make");
  Check(TIFFSetField(tif, TIFFTAG_MODEL, s.model.c_str()), path, "Model");
  Check(TIFFSetField(tif, TIFFTAG_ORIENTATION, static_cast<uint16_t>(s.orientation)), path, "Orientation");
  const float black[1] = {static_cast<float>(s.black)};
  Check(TIFFSetField(tif, TIFFTAG_BLACKLEVEL, uint16_t{1}, black), path, "BlackLevel");
  const uint32_t white[1] = {static_cast<uint32_t>(s.white)};
  Check(TIFFSetField(tif, TIFFTAG_WHITELEVEL, uint16_t{1}, white), path, "WhiteLevel");
  float cm[9];
  for (int i = 0; i < 9; ++i) cm[i] = static_cast<float>(s.color_matrix1[i]);
  Check(TIFFSetField(tif, TIFFTAG_COLORMATRIX1, uint16_t{9}, cm), path, "ColorMatrix1");
  Check(TIFFSetField(tif, TIFFTAG_CALIBRATIONILLUMINANT1, uint16_t{21}), path, "CalibrationIlluminant1");  // 21: D65
  const float neutral[3] = {static_cast<float>(s.as_shot_neutral[0]), static_cast<float>(s.as_shot_neutral[1]),
                            static_cast<float>(s.as_shot_neutral[2])};
  Check(TIFFSetField(tif, TIFFTAG_ASSHOTNEUTRAL, uint16_t{3}, neutral), path, "AsShotNeutral");
  if (s.cfa) {
    const uint16_t dim[2] = {2, 2};
    const uint8_t rggb[4] = {0, 1, 1, 2};
    Check(TIFFSetField(tif, TIFFTAG_CFAREPEATPATTERNDIM, dim), path, "CFARepeatPatternDim");
    Check(TIFFSetField(tif, TIFFTAG_CFAPATTERN, uint16_t{4}, rggb), path, "CFAPattern");
  }
}

// The EXIF directory (written after IFD 0; IFD 0's pointer is rewritten to it).
inline void WriteExif(TIFF* tif, const DngSpec& s, const std::string& path) {
  Check(TIFFCreateEXIFDirectory(tif) == 0, path, "the EXIF directory");
  Check(TIFFSetField(tif, EXIFTAG_EXPOSURETIME, s.exposure_time_s), path, "ExposureTime");
  Check(TIFFSetField(tif, EXIFTAG_FNUMBER, s.f_number), path, "FNumber");
  const uint16_t iso[1] = {static_cast<uint16_t>(std::lround(s.iso))};
  Check(TIFFSetField(tif, EXIFTAG_ISOSPEEDRATINGS, uint16_t{1}, iso), path, "ISOSpeedRatings");
  Check(TIFFSetField(tif, EXIFTAG_FOCALLENGTH, s.focal_length_mm), path, "FocalLength");
  Check(TIFFSetField(tif, EXIFTAG_LENSMODEL, s.lens.c_str()), path, "LensModel");
  uint64_t offset = 0;
  Check(TIFFWriteCustomDirectory(tif, &offset), path, "the EXIF directory");
  Check(TIFFSetDirectory(tif, 0), path, "IFD 0 (reselect)");
  Check(TIFFSetField(tif, TIFFTAG_EXIFIFD, offset), path, "the ExifIFD pointer");
  Check(TIFFRewriteDirectory(tif), path, "IFD 0 (rewrite)");
}
}  // namespace detail

inline void WriteDng(const std::string& path, const DngSpec& s) {
  const int spp = s.cfa ? 1 : 3;
  if (s.samples.size() != static_cast<size_t>(s.width) * s.height * spp)
    throw Error(path + ": DngSpec::samples holds " + std::to_string(s.samples.size()) + " values, expected " +
                std::to_string(static_cast<size_t>(s.width) * s.height * spp));
  TIFF* tif = TIFFOpen(path.c_str(), "w");
  if (!tif) throw Error(path + ": libtiff cannot create the file");
  try {
    detail::Check(TIFFSetField(tif, TIFFTAG_SUBFILETYPE, uint32_t{0}), path, "NewSubFileType");
    detail::Check(TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(s.width)), path, "ImageWidth");
    detail::Check(TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(s.height)), path, "ImageLength");
    detail::Check(TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, uint16_t{16}), path, "BitsPerSample");
    detail::Check(TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(spp)), path, "SamplesPerPixel");
    detail::Check(TIFFSetField(tif, TIFFTAG_COMPRESSION, s.compression), path, "Compression");
    detail::Check(TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, static_cast<uint16_t>(s.cfa ? 32803 : 34892)), path, "PhotometricInterpretation");
    detail::Check(TIFFSetField(tif, TIFFTAG_PLANARCONFIG, uint16_t{PLANARCONFIG_CONTIG}), path, "PlanarConfiguration");
    detail::Check(TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, static_cast<uint32_t>(s.height)), path, "RowsPerStrip");
    detail::Check(TIFFSetField(tif, TIFFTAG_EXIFIFD, uint64_t{0}), path, "the ExifIFD placeholder");
    detail::SetDngTags(tif, s, path);
    std::vector<uint16_t> row(static_cast<size_t>(s.width) * spp);
    for (int y = 0; y < s.height; ++y) {
      std::copy(s.samples.begin() + static_cast<std::ptrdiff_t>(y) * s.width * spp,
                s.samples.begin() + static_cast<std::ptrdiff_t>(y + 1) * s.width * spp, row.begin());
      detail::Check(TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(y), 0) == 1, path, "a scanline");
    }
    detail::Check(TIFFWriteDirectory(tif), path, "IFD 0");
    detail::WriteExif(tif, s, path);
  } catch (...) {
    TIFFClose(tif);
    throw;
  }
  TIFFClose(tif);
}

// A linear RGB image (0..1 = black..white; above 1 clips) as the DngSpec's samples: the
// LinearRaw RGB itself, or its RGGB mosaic (each photosite keeps its own channel).
inline std::vector<uint16_t> RawSamples(const ImageRGB& linear, const DngSpec& s) {
  std::vector<uint16_t> out;
  out.reserve(static_cast<size_t>(linear.width) * linear.height * (s.cfa ? 1 : 3));
  for (int y = 0; y < linear.height; ++y)
    for (int x = 0; x < linear.width; ++x) {
      if (!s.cfa) {
        for (int c = 0; c < 3; ++c) out.push_back(EncodeRaw(linear.at(x, y, c), s.black, s.white));
      } else {
        const int c = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);
        out.push_back(EncodeRaw(linear.at(x, y, c), s.black, s.white));
      }
    }
  return out;
}

}  // namespace skycal::testing
