// Colour-chart correction (Forza Horizon 3's capture pipeline: a ColorChecker shot through
// the same camera and filter, one chart with the ND filter and one without): find an
// X-Rite ColorChecker Classic (24 patches) in an image with OpenCV's mcc detector, measure
// its patches in linear camera RGB, and fit the 3x3 matrix that takes camera RGB to
// scene-linear Rec.709 (OpenCV's ccm module, CIEDE2000 loss). `skycal chart` writes the
// fit as JSON; `skycal capture --color-correction` / `--chart` applies it to the merged
// frame and records it in the frame's metadata (skycalColorCorrection).
//
//   ChartImage img = LoadChartImage("chart.exr", {});            // linear + clipped flags
//   ChartDetection d = FindColorChecker(img, {});                 // throws: not found, clipped
//   ColorCorrection cc = FitColorCorrection(d.patches);           // cc.matrix, cc.delta_e_after
//   ApplyColorCorrection(cc.matrix, &frame);
//
// No OpenCV in this header.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/color_difference.h"
#include "skycal/core/image.h"

namespace skycal::capture {

inline constexpr int kChartPatches = 24;
using ChartColors = std::array<Rgb, kChartPatches>;  // patch 1 (dark skin) .. 24 (black), row by row
using Matrix3 = std::array<double, 9>;               // row-major; out = M * in (column vectors)

// The ColorChecker Classic's patches as published by X-Rite in sRGB (8-bit, D65), decoded
// to linear Rec.709: the reflectance a perfect camera would record under a D65 light of
// unit illuminance (white 9.5 = 0.89). Names as printed on the chart.
const ChartColors& ColorCheckerLinearRec709();
const char* ColorCheckerPatchName(int index);  // 0-based

// An image that shows a chart, in linear camera RGB, and which of its pixels are clipped.
struct ChartImage {
  std::string path;           // named in every error
  ImageRGB linear;            // camera RGB, linear (any scale)
  std::vector<uint8_t> clipped;  // per pixel 1: some channel at full scale (or not measured)
};
// EXR (linear; pixels not finite, a `mask.valid` plane < 0.5, or on a plateau of the
// image's maximum are clipped) or an 8/16-bit image (PNG, TIFF, JPEG) linearised through
// `response_curve` (levels * 3 values per code, R G B interleaved, as MergeResult::
// response_curve; empty: the codes are linear); a channel at the top code is clipped. A
// camera RAW file (IsRawPath) is decoded linear by LibRaw (raw_decode.h; the curve is not
// applied), its saturated pixels clipped.
// Throws skycal::Error naming the file.
ChartImage LoadChartImage(const std::string& path, const std::vector<float>& response_curve);

struct ChartOptions {
  // The chart's outer corners in pixels, x,y x4: the corner at patch 1 (dark skin) first,
  // then clockwise as the chart is seen (the corners at patch 6, 24, 19). Unset: detected
  // by OpenCV mcc.
  std::optional<std::array<double, 8>> corners;
  // A patch is averaged over its central square of this fraction of its side (the rest,
  // near the black gaps, is left out: the detector's corners are good to a few pixels).
  double patch_fraction = 0.5;
  int min_patch_pixels = 4;           // fewer sampled pixels per patch: the chart is too small
  double max_clipped_fraction = 0.01; // more clipped pixels in a patch: refused
  bool IsValid(std::string* why) const;
};

struct ChartDetection {
  std::array<double, 8> corners{};  // as ChartOptions::corners
  std::string method;               // "mcc" or "user corners"
  double detection_ev = 0.0;        // mcc: exposure of the 8-bit image it found the chart in
  ChartColors patches{};            // linear camera RGB, mean of each patch's central square
  std::array<int, kChartPatches> pixels{};
};
// Throws skycal::Error naming the image's path: no chart found (at any of the exposures
// tried), a chart whose neutral patches are not ordered white to black (a false detection
// or a wrongly ordered set of corners), too few pixels per patch, a clipped patch (names
// the patch and the fraction clipped), corners outside the image.
ChartDetection FindColorChecker(const ChartImage& image, const ChartOptions& options);

// Mean over the neutral patches (19..24) of Rec.709 luminance: the exposure scale ColorChecker
// DeltaE2000 divides out (the light on a chart is not known).
double NeutralLuminance(const ChartColors& rgb);
// Per patch CIEDE2000 of `rgb` (linear Rec.709, any scale) against ColorCheckerLinearRec709(),
// after scaling `rgb` so that its NeutralLuminance equals the reference's.
std::array<double, kChartPatches> ChartDeltaE2000(const ChartColors& rgb);

struct ColorCorrection {
  Matrix3 matrix{1, 0, 0, 0, 1, 0, 0, 0, 1};
  // Per patch CIEDE2000 (ChartDeltaE2000) of the camera values taken as Rec.709, and after
  // the matrix.
  std::array<double, kChartPatches> delta_e_before{}, delta_e_after{};
  std::string source;       // the chart image
  std::string source_sha256;
  std::string label;        // e.g. "nd" / "no-nd": which exposure set it belongs to
  double ccm_loss = 0.0;    // OpenCV ccm's final loss (its own CIEDE2000 mean)
  nlohmann::json detection; // corners, method, exposure, pixels per patch
};
// Fits the 3x3 to the patches (linear camera RGB, any scale): OpenCV ccm, CCM_3x3, identity
// linearisation, CIEDE2000 distance, least-squares start. The matrix is then scaled so the
// neutral patches keep their mean camera value as luminance: a neutral colour cast (an
// exposure difference) gives the identity, and the frame's photometric scale (exposure
// factors) is not changed by a correction. Throws skycal::Error when the patches are not
// finite and positive.
ColorCorrection FitColorCorrection(const ChartColors& measured);

void ApplyColorCorrection(const Matrix3& m, ImageRGB* image);
Matrix3 MultiplyMatrices(const Matrix3& a, const Matrix3& b);
Rgb Apply(const Matrix3& m, const Rgb& v);

// JSON (`skycal chart --out`): format "skycal.color_correction", version 1, matrix (row-major,
// camera RGB -> linear Rec.709), delta_e2000 {before, after: mean, max, per_patch}, source,
// sha256, label, detection. FromJson throws skycal::Error naming `what` (the file) and the
// field.
nlohmann::json ColorCorrectionToJson(const ColorCorrection& c);
ColorCorrection ColorCorrectionFromJson(const nlohmann::json& j, const std::string& what);

}  // namespace skycal::capture

namespace skycal::capture {
// LoadChartImage + FindColorChecker + FitColorCorrection, with source, sha256, label and the
// detection filled in: what `skycal chart` and `skycal capture --chart` run.
ColorCorrection CorrectionFromChartImage(const std::string& path, const std::vector<float>& response_curve,
                                         const ChartOptions& options, const std::string& label);
}  // namespace skycal::capture
