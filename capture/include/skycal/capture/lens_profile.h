// Lens profiles from the lensfun database (lensfun 0.3, Debian liblensfun-dev and its XML
// database liblensfun-data-v1): the camera and lens of a photo found by their EXIF names,
// or named explicitly, and the profile's corrections applied to a LINEAR image:
//   vignetting  lensfun's "pa" model (Pablo d'Angelo's, Hugin's): the lens multiplies the
//               radiance by c(r) = 1 + k1 r^2 + k2 r^4 + k3 r^6; the correction divides by it.
//   TCA         lateral chromatic aberration as a radial scale of red and blue against
//               green: the corrected channel at radius r_u is the observed one at
//                 linear  r_d = k r_u                       (kr, kb)
//                 poly3   r_d = r_u (b r_u^2 + c r_u + v)   (br, cr, vr; bb, cb, vb)
//   distortion  the radius of the lens's ideal projection (its lensfun type) mapped to the
//               observed one, poly3 r_d = r_u (1 - k1 + k1 r_u^2), poly5 r_d = r_u (1 + k1
//               r_u^2 + k2 r_u^4), ptlens r_d = r_u (a r_u^3 + b r_u^2 + c r_u + 1 - a - b - c).
// Normalisation (lensfun 0.3.3 libs/lensfun/modifier.cpp, "About coordinate systems in
// Lensfun" and lfModifier::lfModifier; mod-color.cpp, AddColorCallbackVignetting): r is
// measured from the image centre, the image spanning the outer pixel centres (W-1 by H-1,
// centre ((W-1)/2, (H-1)/2)). With D = that half-diagonal in pixels, A the calibration's
// aspect ratio (3:2 unless the XML says otherwise) and k = camera crop / calibration crop:
//   vignetting       r = 1 at D / k: the image corner (the half-diagonal) for the calibration's sensor;
//   TCA, distortion  r = 1 at D k^-1 / sqrt(1 + A^2): half the shorter side when the image has
//                    the calibration's aspect ratio (lensfun's "r = 1 at the middle of the
//                    long edge"), otherwise the calibration sensor's fitted through the diagonal.
// Crop factors are defined by the diagonal, so that is what carries a calibration between
// sensors (lensfun's coordinate_correction).
// The corrections themselves run through lensfun's lfModifier, so they are lensfun's own.
//
// The lens's projection maps onto lens.h's models where one exists: lensfun "fisheye"
// (equidistant), "equisolid" and "stereographic"; rectilinear, orthographic, Thoby and
// panoramic lenses have none (their distortion is still corrected to the ideal projection).
// The focal length gives the image circle: f_px = f_real_mm * crop * (half-diagonal in
// pixels) / 21.633 mm (the 35 mm frame's half-diagonal; lensfun's NormalizedInMillimeters).
#pragma once
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/lens.h"
#include "skycal/core/image.h"

namespace skycal::capture {

// What identifies a photo's camera, lens and settings: its EXIF, or an explicit name.
struct LensQuery {
  std::string camera_maker, camera_model;  // Exif.Image.Make, Exif.Image.Model
  std::string lens_maker, lens_model;      // Exif.Photo.LensMake, Exif.Photo.LensModel (else the maker note's)
  double focal_mm = NAN;                   // Exif.Photo.FocalLength (the lens's, not 35 mm equivalent)
  double f_number = NAN;                   // Exif.Photo.FNumber
  // Focus distance, metres: the sky is at infinity; 1000 m is lensfun's "infinity" row.
  double distance_m = 1000.0;
  bool explicit_spec = false;              // from ParseLensProfileSpec, not EXIF
  std::string Describe() const;            // "camera 'SONY' 'NEX-7', lens 'Samyang ...'" (what was searched)
};

// The names and settings in an image's EXIF; fields stay empty / NAN where absent or
// unreadable (never throws for a file without EXIF; throws skycal::Error when the file
// does not exist).
LensQuery ReadLensQuery(const std::string& image_path);
// Writes Make, Model, LensMake, LensModel, FocalLength (NAN: left out) into an image's EXIF
// block in place (tests and tools that tag synthetic brackets). Throws skycal::Error.
void WriteLensQuery(const std::string& image_path, const LensQuery& q);

// The explicit form (CaptureOptions::lens_profile): "LENS_MAKER:LENS_MODEL", optionally
// followed by "@CAMERA_MAKER:CAMERA_MODEL", each as lensfun names them (lensfun-db XML
// <maker>/<model>; e.g. "Samyang:Samyang 8mm f/2.8 UMC Fish-eye@Sony:NEX-7"). The split is
// at the first ':' of each part. False with the reason in *why when malformed.
bool ParseLensProfileSpec(const std::string& spec, LensQuery* query, std::string* why);

struct LensfunHandle;  // the loaded database and the matched lens (lens_profile.cc)

struct LensProfile {
  LensQuery query;                          // what was searched
  std::string camera_maker, camera_model;   // lensfun's names; empty: no camera matched
  std::string lens_maker, lens_model;       // lensfun's names
  std::string lens_type;                    // lensfun's: rectilinear, fisheye, equisolid, stereographic, ...
  std::optional<LensModel> projection;      // the lens.h model of that type, where one exists
  double crop_factor = NAN;                 // the photo's sensor: the camera's, else the lens calibration's
  double calibration_crop_factor = NAN, calibration_aspect_ratio = NAN;
  double focal_mm = NAN, real_focal_mm = NAN, f_number = NAN, distance_m = NAN;  // the settings used
  double center_offset_x = 0.0, center_offset_y = 0.0;  // lensfun's lens centre shift (r = 1 units)
  // The calibration interpolated at those settings; nullopt where the profile has none (or
  // a setting it needs is unknown): `missing` says which and why.
  std::optional<std::array<double, 3>> vignetting_k;     // pa k1, k2, k3
  std::optional<std::string> tca_model;                  // "linear" or "poly3"
  std::array<double, 6> tca_terms{};                     // lensfun order: linear kr, kb; poly3 vr, vb, cr, cb, br, bb
  std::optional<std::string> distortion_model;           // "poly3", "poly5" or "ptlens"
  std::array<double, 3> distortion_terms{};
  std::vector<std::string> missing;                      // e.g. "tca: the profile has no TCA data for this lens"
  std::vector<std::string> other_matches;                // further lenses that matched the names as well
  std::vector<std::string> notes;                        // e.g. an EXIF focal length a prime lens overrides
  std::shared_ptr<const LensfunHandle> handle;
  nlohmann::json ToJson() const;
};

struct LensLookup {
  std::optional<LensProfile> profile;
  std::string message;                  // no match: what was searched, what was found, the closest
  std::vector<std::string> candidates;  // no lens match: the closest lenses, "MAKER:MODEL"
};

// Finds the camera and lens (lensfun's FindCameras / FindLenses, its fuzzy word match) and
// interpolates the calibration at the query's focal length, f-number and distance. A prime
// lens uses its own focal length (notes says so where the query's differs); vignetting
// needs the f-number. database_dir: lensfun's
// XML folder; empty: the system's (lfDatabase::Load: the user's updates, then
// /usr/share/lensfun/version_1). Throws skycal::Error when no database can be loaded.
LensLookup FindLensProfile(const LensQuery& query, const std::string& database_dir = "");

// Which of a profile's corrections to apply (the caller's hand-given values override).
struct LensCorrections {
  bool vignetting = true, tca = true, distortion = true;
};

// Applies the profile's vignetting, TCA and distortion to a linear image in place (through
// lensfun's lfModifier; TCA and distortion resample each channel bilinearly, positions
// outside the image clamped to its edge). Returns what was applied: {"vignetting": bool,
// "tca": bool, "distortion": bool, "ms": ...}. `threads` as in hdr_merge (0: all cores).
nlohmann::json ApplyLensProfile(const LensProfile& profile, const LensCorrections& which, ImageRGB* linear,
                                int threads = 0);

// The image circle from the profile for a width x height image: the projection (unless
// keep_model), centre (unless keep_center) and, where the model in use is the profile's
// projection, the radius (unless keep_radius: f_px at fov/2;
// when that circle reaches beyond the image's farthest corner and !keep_fov, the fov is
// narrowed to what the corner sees). distortion_corrected: the image is the ideal
// projection (its focal length is lensfun's Hugin-corrected one). Appends what was taken
// to *report. Does not validate (the caller's LensParams::IsValid does).
void LensFromProfile(const LensProfile& profile, int width, int height, bool distortion_corrected, bool keep_model,
                     bool keep_center, bool keep_radius, bool keep_fov, LensParams* lens, nlohmann::json* report);

}  // namespace skycal::capture
