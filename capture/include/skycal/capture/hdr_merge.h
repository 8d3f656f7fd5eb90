// Merging exposure brackets into one linear HDR image (the first step of `skycal capture`,
// Wood, Forza Horizon 3 skies, GDC: 7 exposures per frame, f/8, ISO ramped with the light, data kept linear).
//
//   auto brackets = LoadBrackets(paths, {});          // times, f-number, ISO from EXIF
//   MergeOptions options;                             // auto response, hat weights
//   MergeResult r = MergeBrackets(brackets, options); // r.radiance, r.well_measured, r.report
//
// Units: the radiance is the camera's linearised value (0..1 = black..full scale) divided by
// the bracket's exposure factor k = t * (ISO / 100) / N^2 (t in seconds, N the f-number),
// i.e. multiplied by N^2 / (t * ISO/100): a value of 1 is a scene point that a camera at
// t = 1 s, f/1, ISO 100 would record at full scale. Frames of a time-lapse taken with
// different exposure settings therefore share one scale (given one response curve: pass
// MergeResult::response_curve of a calibration frame as MergeOptions::response_curve).
// The f-number (ISO) enters k only when every bracket has one; when none has, it is left out
// (k = t for PNGs without EXIF) and the report says so; some-but-not-all is an error.
//
// No OpenCV in this header: images are plain code-value buffers.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/core/image.h"

namespace skycal::capture {

// How code values map to linear sensor values.
enum class ResponseModel {
  kAuto,       // recovered: `weighted` per channel first; when the channels' recovered curves have one
               // shape (MergeOptions::auto_shape_tolerance), one `debevec` curve fitted to the three
               // channels together instead (capture/src/camera_response.cc)
  kWeighted,   // recovered from the brackets: Debevec & Malik's log least squares over thousands of
               // samples with inverse-noise-variance weights (capture/src/weighted_response.cc)
  kDebevec,    // recovered from the brackets: Debevec & Malik 1997 least squares on sampled pixels
  kRobertson,  // recovered from the brackets: Robertson et al. 2003 iteration on (subsampled) pixels
  kLinear,     // code / max code (raw developed to linear TIFF/PNG)
  kSrgb,       // inverse sRGB transfer function (IEC 61966-2-1), e.g. camera JPEGs
};
const char* ResponseModelName(ResponseModel m);  // "weighted", "debevec", "robertson", "linear", "srgb"
// Parses the names above; throws skycal::Error naming `what` (e.g. "MergeOptions::response") otherwise.
ResponseModel ParseResponseModel(const std::string& name, const std::string& what);

// Well-exposedness weight of a normalised code value v = code / max code, in [0, 1].
enum class WeightFunction {
  kHat,       // 1 - |2v - 1| (Debevec's triangle)
  kGaussian,  // exp(-(v - 0.5)^2 / (2 sigma^2)) (Mertens' well-exposedness)
};

// A decoded bracket image: code values as stored in the file, R, G, B interleaved, row 0 at
// the top (note: RGB order, unlike OpenCV's BGR).
struct BracketImage {
  int width = 0;
  int height = 0;
  int bits = 8;                 // 8 or 16
  std::vector<uint16_t> rgb;    // width * height * 3 code values in [0, max_code()]
  // Camera RAW (raw_decode.h): codes proportional to light, black 0, white level = max code.
  // Brackets that are all linear skip response recovery (the response is the identity).
  bool linear = false;
  // Per pixel, empty or width * height: 1 = a photosite at or above the white level fed this
  // pixel (RAW); its samples in this bracket get weight 0 in the merge, like a clipped code.
  std::vector<uint8_t> saturated;

  int max_code() const { return bits == 16 ? 65535 : 255; }
  bool empty() const { return width <= 0 || height <= 0; }
  size_t index(int x, int y) const { return (static_cast<size_t>(y) * width + x) * 3; }
};

struct Bracket {
  std::string path;          // the source file (or a label for in-memory images); named in errors
  BracketImage image;
  double exposure_time_s = NAN;
  double f_number = NAN;     // NAN: unknown
  double iso = NAN;          // ISO speed (ISO 12232 / EXIF ISOSpeedRatings); NAN: unknown
  // Camera RAW: camera RGB (image's codes / max code) -> linear Rec.709, 3x3 row-major
  // (RawImage::camera_to_rec709), applied after the merge; empty for other images.
  std::vector<double> camera_to_rec709;
};

struct MergeOptions {
  // auto: weighted's per-channel curves, or one Debevec curve for the three channels (with
  // the EMoR prior, emor_prior below) when they share one shape; how close each method comes
  // to the known-response merge, on the project's curves and on two held-out families:
  // bench/results/capture-response/capture-response.md (docs/capture.md). It costs a weighted
  // recovery plus, for one shape, a Debevec one, once per calibration frame when a time-lapse
  // reuses the curve.
  ResponseModel response = ResponseModel::kAuto;
  // A fixed response (e.g. MergeResult::response_curve of an earlier merge), which skips
  // calibration and keeps a time-lapse on one scale: levels * 3 linear values, R G B
  // interleaved per code, levels = 256 (any bit depth: 16-bit codes are interpolated) or
  // 65536 (16-bit brackets only). Empty: use `response`.
  std::vector<float> response_curve;
  int samples = 70;           // Debevec: pixel locations (OpenCV's default count), spread over brightness
  // Smoothness weight of the curve's second difference in ln (Debevec; Robertson's curve
  // step too), on OpenCV's scale (the ratio to the data weights is the same). 100, not
  // OpenCV's 10: on synthetic 7-bracket sets (tests/synthetic_brackets.h, linear, sRGB and
  // filmic camera curves, photon noise) the p95 radiance error fell from 4.7-6.6% to
  // 3.0-3.2% (the true curve gives 2.9%) and the spread of the channels' scales from up to
  // 8% to under 3%; the error of the overall scale (a gauge, see response_curve) stayed
  // under 10% (8.8% vs 7.5% at worst).
  double lambda = 100.0;
  // skycal's Debevec solves (debevec, and auto's shared curve): brackets a constant step
  // apart cannot tell a curve from the same curve plus any wiggle periodic in that step
  // (capture/src/emor_prior.h). After the solve, the EMoR camera-curve model (Grossberg &
  // Nayar 2004, its first emor_coefficients of 6) is fitted to the samples, and the curve's
  // periodic part is taken from it instead of from the smoothness term: the wiggle a camera
  // would have; what the samples do determine stays Debevec's. Not used when the steps are
  // not multiples of one step or the fitted EMoR curve does not increase (the report says
  // which). bench/results/capture-response/capture-response.md.
  bool emor_prior = true;
  int emor_coefficients = 6;
  // kWeighted: pixel samples per channel, smoothness (the data term is in chi-square units
  // of 1 DN of code noise, so this does not scale with the sample count), reweighting
  // passes and the codes fitted (the curve past them is extrapolated log-linearly).
  int weighted_samples = 8000;
  // 3e5 and 5 passes: the best worst case over lambda 1e3..3e6, 2..5 passes, 8000..60000
  // samples on the bench's 4 shapes x 3 bracket sets (bench/results/capture-response/capture-response.md).
  double weighted_lambda = 3e5;
  int weighted_iterations = 5;
  int weighted_low_code = 3;
  int weighted_high_code = 252;
  // kAuto: the channels' curves count as one shape when the RMS over the fit codes of the
  // difference of their recovered ln f (weighted), each channel's mean removed (the
  // per-channel scale is a gauge), is at most this (natural log units). Measured (the
  // capture-response suite): curves shared by the channels 0.005-0.042, three different
  // curves 0.74-1.43; 0.15 is about the geometric middle (3.5x and 5x away).
  double auto_shape_tolerance = 0.15;
  int robertson_max_iterations = 50;     // from a linear start it converges in ~25-35 (measured)
  double robertson_threshold = 0.001;    // Robertson: stop when the curve's mean |change of ln| per code is below
                                         // this (with opencv_calibration: OpenCV's criterion, default 0.01)
  // Robertson: pixels used (stride-subsampled), 0 = all. 16384 fits the curve as well as
  // 262144 on the synthetic sets (radiance error equal to 3 digits) in a third of the time.
  int calibration_max_pixels = 16384;
  // Recovered curves fit only well-exposed samples (weights below), so clipped and black
  // samples, whose code says nothing of their radiance, cannot bend the curve's ends; the
  // ends are extrapolated. true: cv::CalibrateDebevec / cv::CalibrateRobertson as they are
  // (they fit every sample; the baseline the tests compare against).
  bool opencv_calibration = false;
  WeightFunction weight = WeightFunction::kHat;
  double gaussian_sigma = 0.2;           // kGaussian width, normalised code units
  // A sample is well exposed when low_threshold < v < high_threshold (v = code / max code);
  // others get weight 0. high: a little below the clip (JPEG ringing, highlight roll-off);
  // low: the noise / quantisation floor.
  double low_threshold = 0.02;
  double high_threshold = 0.98;
  // Also weight each sample by its exposure factor k (inverse of photon-noise variance of
  // the radiance estimate code->linear / k), so longer exposures count more where valid.
  bool exposure_weighting = true;
  int threads = 0;            // worker threads (calibration channels, merge rows); 0 = hardware concurrency

  bool IsValid(std::string* why) const;  // names the field at fault
};
nlohmann::json MergeOptionsToJson(const MergeOptions& options);  // written next to outputs

// Per-pixel flags (MergeResult::flags), bits OR-ed over the channels.
enum PixelFlag : uint8_t {
  // A channel has no well-exposed sample and ...
  kPixelOverExposed = 1,   // is clipped even in the shortest bracket: that bracket's value (a lower bound)
  kPixelUnderExposed = 2,  // is black even in the longest bracket: that bracket's value (an upper bound)
  kPixelGap = 4,           // neither: black in some brackets, clipped in the others (spacing too wide,
                           // motion): midway between the two bounds
};

struct MergeResult {
  ImageRGB radiance;                 // linear, units above; every value finite and >= 0
  std::vector<float> well_measured;  // per pixel 1: every channel had >= 1 well-exposed sample; else 0
  std::vector<uint8_t> flags;        // per pixel PixelFlag bits
  long long well_measured_pixels = 0;
  long long under_exposed = 0;       // pixels with kPixelUnderExposed
  long long over_exposed = 0;        // pixels with kPixelOverExposed
  long long gap = 0;                 // pixels with kPixelGap
  long long not_well_measured = 0;   // pixels with any flag (= total - well_measured_pixels)
  // 1 / k of the middle bracket (by exposure): radiance / exposure_scale is that bracket's
  // linearised image, a natural preview exposure.
  double exposure_scale = 1.0;
  std::vector<double> exposure_factors;  // k per bracket, input order
  bool exposure_uses_aperture_iso = false;  // f-number and/or ISO entered k (report: which); false: k = t
  // Linear value per code and channel, R G B interleaved (response_levels * 3), normalised
  // so the top code maps to 1 in every channel (a white clip is neutral). A recovered
  // curve's absolute scale is a gauge the brackets cannot fix; this convention fixes it,
  // with the top code's value extrapolated from the well-exposed codes (measured on
  // synthetic sets: within 10% of the true curve's, channels within 6% of each other).
  std::vector<float> response_curve;
  int response_levels = 0;
  nlohmann::json report;             // brackets, counts, response, options, timings_ms, warnings (strings: e.g. a
                                     // recovered curve these brackets do not determine, response.determinacy)
};

// Merges brackets of one scene (same size and bit depth, distinct exposures, >= 2). Throws
// skycal::Error naming the bracket (its path) and field: size or depth mismatch, fewer than
// two brackets, exposure time missing / non-finite / <= 0, two brackets with the same
// exposure, f-number / ISO known for some brackets but not others, invalid options.
MergeResult MergeBrackets(const std::vector<Bracket>& brackets, const MergeOptions& options);

// Reads an 8- or 16-bit JPEG, PNG or TIFF (libjpeg, libpng, libtiff: grey expanded to RGB,
// alpha dropped, the EXIF orientation applied). Throws skycal::Error naming the file when it
// is unreadable, another format, or of another depth (float TIFF: not a camera bracket).
BracketImage ReadBracketImage(const std::string& path);

// Reads the brackets and their exposures. `exposure_times_s` empty: every time comes from
// the file's EXIF ExposureTime; otherwise one time per path (it wins over EXIF). FNumber and
// ISOSpeedRatings come from EXIF when present. Camera RAW files (IsRawPath, raw_decode.h)
// are decoded by LibRaw to linear camera RGB with a saturation mask and their matrix to
// Rec.709 (Bracket::camera_to_rec709), their exposure read from the RAW metadata. Throws skycal::Error naming the file: when
// unreadable, or with no explicit time and no EXIF ExposureTime; naming the option when the
// counts differ. `report` (optional) receives per-file sources and timings_ms.
std::vector<Bracket> LoadBrackets(const std::vector<std::string>& paths, const std::vector<double>& exposure_times_s,
                                  int threads = 0, nlohmann::json* report = nullptr);

}  // namespace skycal::capture
