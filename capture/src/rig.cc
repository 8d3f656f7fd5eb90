#include "skycal/capture/rig.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

constexpr const char* kFormat = "skycal-rig";
constexpr int kFormatVersion = 1;

using Mat3 = std::array<double, 9>;

Mat3 Mul(const Mat3& a, const Mat3& b) {
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i * 3 + j] += a[i * 3 + k] * b[k * 3 + j];
  return c;
}

// ---------------------------------------------------------------------------------------
// Rig description parsing

std::string Field(const std::string& source, const std::string& field) { return source + ": field '" + field + "'"; }

void CheckKeys(const nlohmann::json& obj, const std::vector<std::string>& allowed, const std::string& source,
               const std::string& prefix) {
  RequireKnownKeys(obj, allowed, source, prefix);
}

double Number(const nlohmann::json& j, const std::string& source, const std::string& field) {
  if (!j.is_number()) throw Error(Field(source, field) + ": expected a number, got " + j.dump());
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw Error(Field(source, field) + ": expected a finite number");
  return v;
}

template <size_t N>
std::array<double, N> Numbers(const nlohmann::json& j, const std::string& source, const std::string& field) {
  if (!j.is_array() || j.size() != N) {
    throw Error(Field(source, field) + ": expected an array of " + std::to_string(N) + " numbers, got " + j.dump());
  }
  std::array<double, N> out;
  for (size_t i = 0; i < N; ++i) out[i] = Number(j[i], source, field + "[" + std::to_string(i) + "]");
  return out;
}

const nlohmann::json& Required(const nlohmann::json& obj, const char* key, const std::string& source, const std::string& prefix) {
  if (!obj.contains(key)) throw Error(Field(source, prefix + key) + " is missing");
  return obj.at(key);
}

Mat3 ParseRotation(const nlohmann::json& j, const std::string& source, const std::string& field) {
  const std::string expected =
      ": expected {\"yaw_deg\": Y, \"pitch_deg\": P, \"roll_deg\": R} (degrees) or a 3x3 camera-to-world rotation matrix "
      "[[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]]";
  if (j.is_object()) {
    CheckKeys(j, {"yaw_deg", "pitch_deg", "roll_deg"}, source, field + ".");
    for (const char* key : {"yaw_deg", "pitch_deg"}) {
      if (!j.contains(key)) {
        throw Error(Field(source, field + "." + key) + " is missing (expected yaw_deg, pitch_deg and optionally roll_deg, in degrees)");
      }
    }
    const double yaw = Number(j.at("yaw_deg"), source, field + ".yaw_deg");
    const double pitch = Number(j.at("pitch_deg"), source, field + ".pitch_deg");
    const double roll = j.contains("roll_deg") ? Number(j.at("roll_deg"), source, field + ".roll_deg") : 0.0;
    return RotationFromYawPitchRollDeg(yaw, pitch, roll);
  }
  if (!j.is_array() || j.size() != 3) throw Error(Field(source, field) + expected + ", got " + j.dump());
  Mat3 r;
  for (int row = 0; row < 3; ++row) {
    const auto& jr = j[row];
    if (!jr.is_array() || jr.size() != 3) throw Error(Field(source, field) + expected + ", got " + j.dump());
    for (int c = 0; c < 3; ++c) {
      r[row * 3 + c] = Number(jr[c], source, field + "[" + std::to_string(row) + "][" + std::to_string(c) + "]");
    }
  }
  std::string why;
  if (!IsRotation(r, &why)) throw Error(Field(source, field) + ": " + why);
  return r;
}

LensParams ParseLens(const nlohmann::json& j, int w, int h, const std::string& source, const std::string& prefix) {
  if (!j.is_object()) throw Error(Field(source, prefix.substr(0, prefix.size() - 1)) + ": expected an object");
  CheckKeys(j, {"model", "fov_deg", "center", "radius_px", "kb_k", "vignetting"}, source, prefix);
  const auto& jm = Required(j, "model", source, prefix);
  if (!jm.is_string()) throw Error(Field(source, prefix + "model") + ": expected a string, got " + jm.dump());
  const auto model = LensModelFromName(jm.get<std::string>());
  if (!model) {
    throw Error(Field(source, prefix + "model") + ": unknown lens model '" + jm.get<std::string>() +
                "' (expected latlong, equidistant, equisolid, stereographic or kannala-brandt)");
  }
  LensParams lens;
  lens.model = *model;
  const bool latlong = lens.model == LensModel::kLatLong;
  if (latlong) lens = LatLongLens(w, h);
  if (!latlong || j.contains("fov_deg")) lens.fov_deg = Number(Required(j, "fov_deg", source, prefix), source, prefix + "fov_deg");
  if (!latlong || j.contains("center")) {
    const auto c = Numbers<2>(Required(j, "center", source, prefix), source, prefix + "center");
    lens.center_x = c[0];
    lens.center_y = c[1];
  }
  if (!latlong || j.contains("radius_px")) {
    lens.radius_px = Number(Required(j, "radius_px", source, prefix), source, prefix + "radius_px");
  }
  if (lens.model == LensModel::kKannalaBrandt) {
    lens.kb_k = Numbers<4>(Required(j, "kb_k", source, prefix), source, prefix + "kb_k");
  } else if (j.contains("kb_k")) {
    throw Error(Field(source, prefix + "kb_k") + ": applies to the kannala-brandt model only (this lens is " +
                LensModelName(lens.model) + ")");
  }
  if (j.contains("vignetting")) lens.vignetting = Numbers<3>(j.at("vignetting"), source, prefix + "vignetting");
  std::string why;
  if (!lens.IsValid(&why, w, h)) {
    // IsValid's message starts with the field at fault ("radius_px = ...", "kb_k: ...").
    const size_t end = why.find_first_of(" :");
    const std::string key = why.substr(0, end);
    const std::string field = key == "image_size" ? prefix.substr(0, prefix.rfind("lens.")) + key : prefix + key;
    throw Error(Field(source, field) + why.substr(end));
  }
  return lens;
}

std::vector<RigCamera> ParseRig(const nlohmann::json& j, const std::string& source, const std::string& base_dir) {
  if (!j.is_object()) throw Error(source + ": expected a JSON object with a 'cameras' array (a skycal rig description)");
  CheckKeys(j, {"format", "format_version", "cameras"}, source, "");
  if (j.contains("format") && (!j.at("format").is_string() || j.at("format").get<std::string>() != kFormat)) {
    throw Error(Field(source, "format") + ": expected \"" + kFormat + "\" (is this a skycal rig description?)");
  }
  RequireFormatVersion(j, kFormatVersion, source, "add \"format_version\": 1 after checking the file against this version's rig format");
  const auto& jc = Required(j, "cameras", source, "");
  if (!jc.is_array() || jc.empty()) throw Error(Field(source, "cameras") + ": expected a non-empty array of cameras");
  std::vector<RigCamera> cameras;
  for (size_t i = 0; i < jc.size(); ++i) {
    const std::string prefix = "cameras[" + std::to_string(i) + "].";
    const auto& cam = jc[i];
    if (!cam.is_object()) throw Error(Field(source, prefix.substr(0, prefix.size() - 1)) + ": expected an object");
    CheckKeys(cam, {"name", "image", "image_size", "lens", "rotation"}, source, prefix);
    RigCamera rc;
    if (cam.contains("name")) {
      if (!cam.at("name").is_string()) throw Error(Field(source, prefix + "name") + ": expected a string");
      rc.name = cam.at("name").get<std::string>();
    }
    const auto& ji = Required(cam, "image", source, prefix);
    if (!ji.is_string() || ji.get<std::string>().empty()) {
      throw Error(Field(source, prefix + "image") + ": expected an image file name, got " + ji.dump());
    }
    rc.image = ji.get<std::string>();
    if (!base_dir.empty() && std::filesystem::path(rc.image).is_relative()) {
      rc.image = (std::filesystem::path(base_dir) / rc.image).lexically_normal().string();
    }
    const auto& js = Required(cam, "image_size", source, prefix);
    if (!js.is_array() || js.size() != 2 || !js[0].is_number_integer() || !js[1].is_number_integer() ||
        js[0].get<long long>() <= 0 || js[1].get<long long>() <= 0 || js[0].get<long long>() > 1000000 ||
        js[1].get<long long>() > 1000000) {
      throw Error(Field(source, prefix + "image_size") + ": expected [width, height] in pixels (positive integers), got " +
                  js.dump());
    }
    rc.width = js[0].get<int>();
    rc.height = js[1].get<int>();
    rc.lens = ParseLens(Required(cam, "lens", source, prefix), rc.width, rc.height, source, prefix + "lens.");
    rc.rotation = ParseRotation(Required(cam, "rotation", source, prefix), source, prefix + "rotation");
    cameras.push_back(std::move(rc));
  }
  return cameras;
}

// ---------------------------------------------------------------------------------------
// Unwrapping

void ParallelFor(int n, int threads, const std::function<void(int)>& body) {
  threads = std::clamp(threads, 1, std::max(1, n));
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int i; (i = next.fetch_add(1)) < n;) body(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

// Premultiplied RGBA mip-map: level 0 is the image divided by the vignetting gain, with
// alpha 1 inside the image circle and 0 outside or where a channel is not finite.
struct Level {
  int w = 0, h = 0;
  double scale = 1.0;  // level pixels per level-0 pixel: 2^-level
  std::vector<float> rgba;
  const float* at(int x, int y) const { return &rgba[(static_cast<size_t>(y) * w + x) * 4]; }
};

struct Camera {
  const RigCamera* rig = nullptr;
  Mat3 world_to_camera{};  // transpose of rig->rotation
  std::vector<Level> levels;
  bool latlong = false;
  double period = 0.0;  // lat-long: level-0 pixels per 360 degrees (seam wrap)
};

void BuildPyramid(Camera& cam, const ImageRGB& img, int threads) {
  const LensParams& lens = cam.rig->lens;
  Level l0;
  l0.w = img.width;
  l0.h = img.height;
  l0.rgba.assign(static_cast<size_t>(l0.w) * l0.h * 4, 0.0f);
  const double r2max = lens.radius_px * lens.radius_px;
  ParallelFor(l0.h, threads, [&](int y) {
    for (int x = 0; x < l0.w; ++x) {
      const float* p = &img.pixels[img.index(x, y)];
      float* q = &l0.rgba[(static_cast<size_t>(y) * l0.w + x) * 4];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
      double gain = 1.0;
      if (!cam.latlong) {
        const double dx = x - lens.center_x, dy = y - lens.center_y;
        if (dx * dx + dy * dy > r2max) continue;
        gain = VignettingGain(lens, {static_cast<double>(x), static_cast<double>(y)});
      }
      for (int c = 0; c < 3; ++c) q[c] = static_cast<float>(p[c] / gain);
      q[3] = 1.0f;
    }
  });
  cam.levels.push_back(std::move(l0));
  while (cam.levels.back().w > 1 || cam.levels.back().h > 1) {
    const Level& s = cam.levels.back();
    Level d;
    d.w = std::max(1, (s.w + 1) / 2);
    d.h = std::max(1, (s.h + 1) / 2);
    d.scale = 0.5 * s.scale;
    d.rgba.assign(static_cast<size_t>(d.w) * d.h * 4, 0.0f);
    ParallelFor(d.h, threads, [&](int y) {
      const int y0 = std::min(2 * y, s.h - 1), y1 = std::min(2 * y + 1, s.h - 1);
      for (int x = 0; x < d.w; ++x) {
        const int x0 = std::min(2 * x, s.w - 1), x1 = std::min(2 * x + 1, s.w - 1);
        float* q = &d.rgba[(static_cast<size_t>(y) * d.w + x) * 4];
        const float *a = s.at(x0, y0), *b = s.at(x1, y0), *c = s.at(x0, y1), *e = s.at(x1, y1);
        for (int k = 0; k < 4; ++k) q[k] = 0.25f * (a[k] + b[k] + c[k] + e[k]);
      }
    });
    cam.levels.push_back(std::move(d));
  }
}

// Bilinear sample of one level at a level-0 position (clamped to the edge), accumulated
// into acc with weight wt.
void SampleLevel(const Level& lv, double x, double y, double wt, double acc[4]) {
  const double s = lv.scale;
  double qx = (x + 0.5) * s - 0.5, qy = (y + 0.5) * s - 0.5;
  qx = std::clamp(qx, 0.0, static_cast<double>(lv.w - 1));
  qy = std::clamp(qy, 0.0, static_cast<double>(lv.h - 1));
  const int x0 = std::min(static_cast<int>(qx), lv.w - 1), y0 = std::min(static_cast<int>(qy), lv.h - 1);
  const int x1 = std::min(x0 + 1, lv.w - 1), y1 = std::min(y0 + 1, lv.h - 1);
  const double fx = qx - x0, fy = qy - y0;
  const float *a = lv.at(x0, y0), *b = lv.at(x1, y0), *c = lv.at(x0, y1), *d = lv.at(x1, y1);
  const double wa = (1 - fx) * (1 - fy) * wt, wb = fx * (1 - fy) * wt, wc = (1 - fx) * fy * wt, wd = fx * fy * wt;
  for (int k = 0; k < 4; ++k) acc[k] += wa * a[k] + wb * b[k] + wc * c[k] + wd * d[k];
}

// Filtered premultiplied RGBA at image position p for an output pixel whose footprint in
// the image is spanned by the vectors a and b (pixels).
void SampleFootprint(const Camera& cam, double px, double py, const double a[2], const double b[2], int max_aniso,
                     double out[4]) {
  // Footprint ellipse: singular values of [a b] from the eigenvalues of a a^T + b b^T.
  const double sxx = a[0] * a[0] + b[0] * b[0], syy = a[1] * a[1] + b[1] * b[1], sxy = a[0] * a[1] + b[0] * b[1];
  const double tr = 0.5 * (sxx + syy), disc = std::sqrt(std::max(0.0, 0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy));
  const double major = std::sqrt(tr + disc), minor = std::sqrt(std::max(0.0, tr - disc));
  for (int k = 0; k < 4; ++k) out[k] = 0.0;
  const int nlev = static_cast<int>(cam.levels.size());
  if (!(major > 1.0)) {  // the output is finer than the image: bilinear
    SampleLevel(cam.levels[0], px, py, 1.0, out);
    return;
  }
  const int taps = std::clamp(static_cast<int>(std::ceil(major / std::max(minor, 1.0))), 1, max_aniso);
  const double width = std::max({minor, major / taps, 1.0});
  const double lod = std::min(std::log2(width), static_cast<double>(nlev - 1));
  const int l0 = static_cast<int>(lod);
  const int l1 = std::min(l0 + 1, nlev - 1);
  const double t = lod - l0;
  // Long-axis direction: eigenvector of the larger eigenvalue.
  double ux = sxy, uy = (tr + disc) - sxx;
  if (std::abs(ux) + std::abs(uy) < 1e-12 * (sxx + syy)) {
    ux = (tr + disc) - syy;
    uy = sxy;
  }
  const double un = std::hypot(ux, uy);
  if (un > 0) {
    ux /= un;
    uy /= un;
  } else {
    ux = 1.0;
    uy = 0.0;
  }
  for (int i = 0; i < taps; ++i) {
    const double o = taps == 1 ? 0.0 : ((i + 0.5) / taps - 0.5) * major;
    double x = px + o * ux, y = py + o * uy;
    if (cam.latlong) {  // the seam: columns 0 and W-1 are one direction
      if (x < 0) x += cam.period;
      if (x > cam.period) x -= cam.period;
    }
    SampleLevel(cam.levels[l0], x, y, (1.0 - t) / taps, out);
    if (t > 0) SampleLevel(cam.levels[l1], x, y, t / taps, out);
  }
}

// Blend weight: normalised distance to the nearest edge of the image circle or the frame.
double Feather(const Camera& cam, double px, double py, double power) {
  if (cam.latlong) return 1.0;
  const LensParams& lens = cam.rig->lens;
  const Level& l0 = cam.levels[0];
  const double dx = px - lens.center_x, dy = py - lens.center_y;
  const double d = std::min({lens.radius_px - std::sqrt(dx * dx + dy * dy), px + 0.5, l0.w - 0.5 - px, py + 0.5, l0.h - 0.5 - py});
  if (!(d > 0)) return 0.0;
  const double e = std::min(1.0, d / lens.radius_px);
  return power == 2.0 ? e * e : power == 1.0 ? e : std::pow(e, power);
}

std::string CameraLabel(size_t i, const RigCamera& c) {
  std::string s = "camera " + std::to_string(i);
  if (!c.name.empty()) s += " (" + c.name + ")";
  else if (!c.image.empty()) s += " (" + c.image + ")";
  return s;
}

}  // namespace

std::array<double, 9> RotationFromYawPitchRollDeg(double yaw_deg, double pitch_deg, double roll_deg) {
  const double y = yaw_deg * kPi / 180.0, p = -pitch_deg * kPi / 180.0, r = roll_deg * kPi / 180.0;
  const Mat3 ry{std::cos(y), 0, std::sin(y), 0, 1, 0, -std::sin(y), 0, std::cos(y)};
  const Mat3 rx{1, 0, 0, 0, std::cos(p), -std::sin(p), 0, std::sin(p), std::cos(p)};
  const Mat3 rz{std::cos(r), -std::sin(r), 0, std::sin(r), std::cos(r), 0, 0, 0, 1};
  const Mat3 base{-1, 0, 0, 0, -1, 0, 0, 0, 1};
  return Mul(Mul(Mul(ry, rx), rz), base);
}

bool IsRotation(const std::array<double, 9>& r, std::string* why) {
  for (double v : r) {
    if (!std::isfinite(v)) {
      if (why) *why = "expected finite matrix entries";
      return false;
    }
  }
  double err = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double dot = 0.0;
      for (int k = 0; k < 3; ++k) dot += r[k * 3 + i] * r[k * 3 + j];
      err = std::max(err, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (err > 1e-6) {
    if (why) *why = "not a rotation matrix: R^T R differs from the identity by " + std::to_string(err) + " (expected orthonormal columns to 1e-6)";
    return false;
  }
  if (det < 0) {
    if (why) *why = "not a rotation matrix: determinant " + FormatNumber(det) + " (a reflection; expected +1)";
    return false;
  }
  return true;
}

std::vector<RigCamera> ParseRigJson(const std::string& json_text, const std::string& source, const std::string& base_dir) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(source + ": not valid JSON (byte " + std::to_string(e.byte) + "): " + e.what());
  }
  return ParseRig(j, source, base_dir);
}

std::vector<RigCamera> ReadRigFile(const std::string& path) {
  return ParseRig(ReadJsonFile(path), path, std::filesystem::path(path).parent_path().string());
}

namespace {

// Each camera checked against its image (size, lens, rotation) and readied for sampling:
// world-to-camera rotation, lat-long period, mip pyramid.
std::vector<Camera> PrepareCameras(const std::vector<std::pair<RigCamera, const ImageRGB*>>& cameras, int threads) {
  std::vector<Camera> cams(cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    const RigCamera& rc = cameras[i].first;
    const ImageRGB* img = cameras[i].second;
    const std::string label = CameraLabel(i, rc);
    if (!img || img->empty()) throw Error("unwrap: " + label + ": no image");
    if (img->pixels.size() != static_cast<size_t>(img->width) * img->height * 3) {
      throw Error("unwrap: " + label + ": image has " + std::to_string(img->pixels.size()) + " floats, expected width x height x 3");
    }
    if ((rc.width || rc.height) && (img->width != rc.width || img->height != rc.height)) {
      throw Error("unwrap: " + label + ": image is " + std::to_string(img->width) + "x" + std::to_string(img->height) +
                  ", the rig states image_size " + std::to_string(rc.width) + "x" + std::to_string(rc.height));
    }
    std::string why;
    if (!rc.lens.IsValid(&why, img->width, img->height)) throw Error("unwrap: " + label + ": lens " + why);
    if (!IsRotation(rc.rotation, &why)) throw Error("unwrap: " + label + ": rotation " + why);
    Camera& c = cams[i];
    c.rig = &rc;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) c.world_to_camera[a * 3 + b] = rc.rotation[b * 3 + a];
    c.latlong = rc.lens.model == LensModel::kLatLong;
    c.period = img->width - 1;
    BuildPyramid(c, *img, threads);
  }
  return cams;
}

// The output lat-long's columns (sin and cos of longitude) and its steps in radians per pixel.
struct OutputGrid {
  int width = 0, height = 0;
  std::vector<double> sin_lon, cos_lon;
  double dlon_dx = 0.0, dlat_dy = 0.0;
};

// Per output node of row y: world direction, its derivatives along x and y (the node's
// footprint) and (r, g, b, weight) summed over the cameras, feather-weighted.
std::vector<double> UnwrapRowSums(const std::vector<Camera>& cams, const OutputGrid& grid, int y, int max_aniso,
                                  const UnwrapOptions& options) {
  const int width = grid.width, height = grid.height;
  const std::vector<double>& sin_lon = grid.sin_lon;
  const std::vector<double>& cos_lon = grid.cos_lon;
  const double dlon_dx = grid.dlon_dx, dlat_dy = grid.dlat_dy;
  const double lat = latlong::Latitude(y, height);
  const double sl = std::sin(lat), cl = std::cos(lat);
  // Width of the node's footprint across longitude: the mean cos(latitude) over its band of
  // +-half a row (core/latlong.h PixelSolidAngle), not zero at the poles.
  const double top = std::min(lat - 0.5 * dlat_dy, kPi / 2), bottom = std::max(lat + 0.5 * dlat_dy, -kPi / 2);
  const double c_band = (std::sin(top) - std::sin(bottom)) / (top - bottom);
  std::vector<double> acc(static_cast<size_t>(width) * 4, 0.0);
  std::vector<Vec3d> world(width), tx(width), ty(width), rays(width);
  std::vector<Vec2d> pix(width);
  std::vector<unsigned char> valid(width);
  std::vector<std::array<double, 6>> jac(width);
  for (int x = 0; x < width; ++x) {
    world[x] = {sin_lon[x] * cl, sl, cos_lon[x] * cl};
    tx[x] = {dlon_dx * cos_lon[x] * c_band, 0.0, -dlon_dx * sin_lon[x] * c_band};
    ty[x] = {-dlat_dy * sin_lon[x] * sl, dlat_dy * cl, -dlat_dy * cos_lon[x] * sl};
  }
  for (const Camera& cam : cams) {
    const Mat3& m = cam.world_to_camera;
    auto apply = [&m](const Vec3d& v) {
      return Vec3d{m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
                   m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
    };
    for (int x = 0; x < width; ++x) rays[x] = apply(world[x]);
    RaysToPixels(cam.rig->lens, rays, pix, valid, jac);
    for (int x = 0; x < width; ++x) {
      if (!valid[x]) continue;
      const double px = pix[x][0], py = pix[x][1];
      const double feather = Feather(cam, px, py, options.feather_power);
      if (!(feather > 0)) continue;
      const Vec3d cx = apply(tx[x]), cy = apply(ty[x]);
      const auto& J = jac[x];
      const double a[2] = {J[0] * cx[0] + J[1] * cx[1] + J[2] * cx[2], J[3] * cx[0] + J[4] * cx[1] + J[5] * cx[2]};
      const double b[2] = {J[0] * cy[0] + J[1] * cy[1] + J[2] * cy[2], J[3] * cy[0] + J[4] * cy[1] + J[5] * cy[2]};
      double s[4];
      SampleFootprint(cam, px, py, a, b, max_aniso, s);
      for (int k = 0; k < 4; ++k) acc[static_cast<size_t>(x) * 4 + k] += feather * s[k];
    }
  }
  return acc;
}

}  // namespace

ImageRGB UnwrapToLatLong(const std::vector<std::pair<RigCamera, const ImageRGB*>>& cameras, int width, int height,
                         std::vector<float>* coverage, const UnwrapOptions& options) {
  if (width < 2 || height < 2) {
    throw Error("unwrap: output size " + std::to_string(width) + "x" + std::to_string(height) + ": expected at least 2x2");
  }
  const int threads = std::max(1, options.threads);
  const int max_aniso = std::max(1, options.max_anisotropy);
  const std::vector<Camera> cams = PrepareCameras(cameras, threads);

  ImageRGB out(width, height);
  if (coverage) coverage->assign(static_cast<size_t>(width) * height, 0.0f);
  OutputGrid grid;
  grid.width = width, grid.height = height;
  std::vector<double>& sin_lon = grid.sin_lon;
  std::vector<double>& cos_lon = grid.cos_lon;
  sin_lon.resize(width), cos_lon.resize(width);
  for (int x = 0; x < width; ++x) {
    const double lon = latlong::Longitude(x, width);
    sin_lon[x] = std::sin(lon);
    cos_lon[x] = std::cos(lon);
  }
  const double dlon_dx = -2.0 * kPi / (width - 1), dlat_dy = -kPi / (height - 1);
  grid.dlon_dx = dlon_dx, grid.dlat_dy = dlat_dy;

  ParallelFor(height, threads, [&](int y) {
    const std::vector<double> acc = UnwrapRowSums(cams, grid, y, max_aniso, options);
    for (int x = 0; x < width; ++x) {
      const double* q = &acc[static_cast<size_t>(x) * 4];
      if (coverage) (*coverage)[static_cast<size_t>(y) * width + x] = static_cast<float>(q[3]);
      if (!(q[3] > 0)) continue;
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = static_cast<float>(q[c] / q[3]);
    }
  });
  return out;
}

}  // namespace skycal::capture
