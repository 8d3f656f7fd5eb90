// Camera RAW brackets (DNG and the camera makers' formats: CR2, CR3, NEF, ARW, RAF, ORF,
// RW2, PEF, ...) decoded through LibRaw (Debian libraw-dev, the thread-safe libraw_r) to
// LINEAR camera RGB: the black level subtracted, the white level scaled to code 65535, no
// white balance, no tone curve, no gamma, no automatic brightening. Such an image needs no
// response recovery (its response is the identity, BracketImage::linear) and is merged in
// the camera's own RGB, where a clipped photosite is clipped in one channel only; the
// camera's matrix to scene-linear Rec.709 (RawImage::camera_to_rec709) is applied to the
// merged radiance afterwards, in floating point (capture_pipeline.cc's colour stage).
//
//   RawImage r = ReadRawImage("IMG_0001.CR2");   // r.image.rgb, r.image.saturated, r.exposure_time_s
//
// Units: code = (raw - black) / (white - black) * 65535 per photosite, so 1 code step is
// (white - black) / 65535 raw units (at most 1 raw unit for a sensor of 16 bits or fewer).
#pragma once
#include <array>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/hdr_merge.h"

namespace skycal::capture {

// What a RAW file says of the camera, lens and shot (LibRaw's imgdata.idata, .other, .lens),
// read without decoding the pixels (ReadRawMetadata) or with them (RawImage::metadata).
struct RawMetadata {
  std::string make, model;          // normalised by LibRaw ("Canon", "EOS 5D Mark IV")
  std::string unique_camera_model;  // DNG UniqueCameraModel; "" for other formats
  std::string lens;                 // lens model (EXIF LensModel or the maker note's), "" if unknown
  std::string lens_make;
  double focal_length_mm = NAN;     // EXIF FocalLength; NAN: unknown
  double exposure_time_s = NAN;     // EXIF ExposureTime; NAN: unknown
  double f_number = NAN;            // EXIF FNumber; NAN: unknown
  double iso = NAN;                 // EXIF ISOSpeedRatings (or the maker note's); NAN: unknown
  int dng_version = 0;              // e.g. 0x01040000 for DNG 1.4; 0: not a DNG
  std::string format;               // "dng", "bayer", "x-trans", "linear" (LibRaw's decoder class)
};

// A decoded RAW bracket.
struct RawImage {
  // 16-bit linear camera RGB (bits = 16, linear = true), rotated to the file's orientation;
  // `saturated` marks every pixel that a photosite at or above the white level fed (for a
  // mosaic, any photosite within the demosaic's 7x7 footprint): the merge gives it weight 0.
  BracketImage image;
  RawMetadata metadata;
  // Camera RGB (as in `image`, code / 65535) -> linear Rec.709 primaries, D65 white, 3x3
  // row-major. Built from LibRaw's rgb_cam and its daylight multipliers pre_mul (the matrix
  // of the DNG's ColorMatrix or of LibRaw's table for the camera), scaled so that a D65
  // grey with green code g comes out as (g, g, g): the units of the merge are kept.
  std::array<double, 9> camera_to_rec709{};
  bool has_matrix = false;          // false: LibRaw knows no matrix for this camera
  double black_level = 0.0;         // raw units, as subtracted (mean of the per-channel levels)
  double white_level = 0.0;         // raw units
  long long saturated_pixels = 0;   // pixels marked in image.saturated
  int flip = 0;                     // LibRaw's orientation code applied (0 none, 3 180 deg, 5 / 6 90 deg)
};

// Whether `path` names a camera RAW file by its extension (case-insensitive): .dng .cr2
// .cr3 .crw .nef .nrw .arw .srf .sr2 .raf .orf .rw2 .rwl .pef .srw .3fr .iiq .erf .kdc .dcr
// .mos .mrw .x3f .raw. Brackets with these extensions are read by ReadRawImage; a DNG is a
// TIFF, so OpenCV would read its preview instead.
bool IsRawPath(const std::string& path);

// Decodes `path` (see above). Throws skycal::Error naming the file when it is missing,
// truncated, corrupt, of a format or layout LibRaw does not decode (Foveon, Fuji SuperCCD,
// a non-RGB colour filter), or has no colour data.
RawImage ReadRawImage(const std::string& path);

// The metadata only (no pixel decoding); throws as ReadRawImage does for unreadable files.
RawMetadata ReadRawMetadata(const std::string& path);

nlohmann::json RawMetadataToJson(const RawMetadata& m);

}  // namespace skycal::capture
