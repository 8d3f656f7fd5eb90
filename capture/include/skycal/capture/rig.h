// A camera rig (e.g. three fisheyes 120 degrees apart) and its stitch into the project's
// lat-long (core/latlong.h).
//
// Rig description file (JSON; relative image paths are relative to the file's folder):
//   {
//     "format": "skycal-rig",                            (optional; checked when present)
//     "format_version": 1,                               (required: a later format is refused, not guessed)
//     "cameras": [
//       {
//         "name": "east",                                  (optional, used in messages)
//         "image": "east.exr",
//         "image_size": [2000, 2000],                      (width, height the lens refers to)
//         "lens": {
//           "model": "equisolid",   latlong | equidistant | equisolid | stereographic | kannala-brandt
//           "fov_deg": 180,         (latlong: 360, may be omitted)
//           "center": [999.5, 999.5],      (pixels; latlong: may be omitted)
//           "radius_px": 1000,             (image circle = fov edge; latlong: may be omitted)
//           "kb_k": [k1, k2, k3, k4],      (kannala-brandt only; required there)
//           "vignetting": [a, b, c]        (optional, default zeros; fisheye models only)
//         },
//         "rotation": {"yaw_deg": 0, "pitch_deg": 30, "roll_deg": 0}
//           or        [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]]  (camera-to-world)
//       }, ...
//     ]
//   }
// Unknown keys are errors (a misspelt key would otherwise be silently ignored). Every
// error names the file and the field, e.g. "rig.json: field 'cameras[1].lens.radius_px'".
#pragma once
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "skycal/capture/lens.h"
#include "skycal/core/image.h"

namespace skycal::capture {

struct RigCamera {
  LensParams lens;
  // Camera-to-world rotation, row-major: world = R * camera (camera frame: lens.h; world =
  // the lat-long frame, +Y up). Its columns are the camera's +X, +Y, +Z in the world.
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::string image;          // image path
  int width = 0, height = 0;  // image size the lens parameters refer to (0 = unstated)
  std::string name;           // for messages; may be empty
};

// Camera-to-world rotation of a camera whose optical axis points at azimuth yaw_deg and
// elevation pitch_deg (the command line's azimuth / elevation, core/latlong.h), rolled by
// roll_deg about that axis (positive: the camera's top edge turns toward its right,
// clockwise seen from behind the camera). At 0, 0, 0 the camera looks along world +Z with
// image up = world +Y and image right = world -X (a level camera facing longitude 0):
// R = diag(-1, -1, 1). R = Ry(yaw) Rx(-pitch) Rz(roll) diag(-1, -1, 1).
std::array<double, 9> RotationFromYawPitchRollDeg(double yaw_deg, double pitch_deg, double roll_deg);

// False, with the reason in *why, unless r is orthonormal with determinant +1 (to 1e-6)
// and finite.
bool IsRotation(const std::array<double, 9>& r, std::string* why);

// Parses a rig description (format above). `source` names the document in messages;
// relative image paths are joined to base_dir (kept as written when base_dir is empty).
// Throws skycal::Error naming source and field: not JSON, missing or mistyped field,
// unknown key or lens model, an invalid lens for its image_size (LensParams::IsValid),
// a malformed rotation (not yaw/pitch/roll degrees or a 3x3 rotation matrix).
std::vector<RigCamera> ParseRigJson(const std::string& json_text, const std::string& source, const std::string& base_dir);
// Reads and parses a rig file; images are relative to its folder.
std::vector<RigCamera> ReadRigFile(const std::string& path);

struct UnwrapOptions {
  int threads = 2;             // output rows are shared among this many threads
  double feather_power = 2.0;  // blend weight (1 - r/R)^p, r/R the normalised distance to the image edge
  int max_anisotropy = 16;     // most filter taps along a footprint's long axis
};

// Stitches the cameras' images into a width x height lat-long (project convention). For
// every output node and camera: the node's ray in the camera frame, its image position,
// and the image footprint of the output pixel (lens Jacobian): a trilinear mip-map sample
// at the footprint's short axis with up to max_anisotropy taps along its long axis (plain
// bilinear where the output is finer than the image). Images are divided by the lens's
// vignetting gain; pixels outside the image circle and non-finite pixels carry no weight
// (filtered as premultiplied alpha, so the circle's edge does not darken the result).
// Cameras blend with weights (1 - d/R)^p, d the distance to the nearest edge of the image
// circle or frame, R = radius_px (lat-long cameras: weight 1), normalised per node.
// coverage (resized to width * height, may be null): the sum of the blend weights at each
// node, 0 where no camera sees (the output is 0 there).
// Throws skycal::Error naming the camera (index and name) when an image is null, empty or
// not its stated size, or the lens or rotation is invalid; or when width < 2 or height < 2.
ImageRGB UnwrapToLatLong(const std::vector<std::pair<RigCamera, const ImageRGB*>>& cameras, int width, int height,
                         std::vector<float>* coverage, const UnwrapOptions& options = {});

}  // namespace skycal::capture
