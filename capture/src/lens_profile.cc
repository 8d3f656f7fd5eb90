// Lens profiles through lensfun 0.3 (lens_profile.h). Why lensfun: it is the one maintained,
// openly licensed (LGPL-3 code, CC-BY-SA-3 data) database of lens calibrations, the one
// darktable, RawTherapee, digiKam and Hugin's fulla read, packaged in Debian with its data.
#include "skycal/capture/lens_profile.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>

#include <lensfun.h>

#include "exiv2_read.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"

// exiv2 0.27's API hands out std::auto_ptr (deprecated since C++11, still in libstdc++).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>

namespace skycal::capture {

// The database stays loaded for the process (parsing its ~50 XML files is the slow part);
// profiles keep it alive and point at one of its lenses.
struct LensfunHandle {
  std::shared_ptr<const lfDatabase> db;
  const lfLens* lens = nullptr;
};

namespace {

using Clock = std::chrono::steady_clock;

// The 35 mm frame's half-diagonal, mm: lensfun's NormalizedInMillimeters before its
// aspect-ratio and crop-factor terms (modifier.cpp: sqrt(36^2 + 24^2) / 2).
constexpr double kHalfDiagonal35mm = 21.633307652783937;

std::string Str(const lfMLstr s) {
  const char* v = s ? lf_mlstr_get(s) : nullptr;
  return v ? std::string(v) : std::string();
}

std::shared_ptr<const lfDatabase> LoadDatabase(const std::string& dir) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const lfDatabase>> loaded;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = loaded[dir];
  if (slot) return slot;
  auto db = std::make_shared<lfDatabase>();
  const bool ok = dir.empty() ? db->Load() == LF_NO_ERROR : db->LoadDirectory(dir.c_str());
  if (!ok || !db->GetLenses() || !db->GetLenses()[0])
    throw Error("lensfun: no lens database found" + (dir.empty() ? std::string(" (lfDatabase::Load: the user's updates, "
                                                                              "/usr/share/lensfun/version_1; Debian "
                                                                              "package liblensfun-data-v1)")
                                                                : " in '" + dir + "'"));
  slot = db;
  return slot;
}

// Lower-case alphanumeric words, for ranking the closest names when nothing matched.
std::set<std::string> Words(const std::string& s) {
  std::set<std::string> w;
  std::string cur;
  for (char ch : s + " ") {
    if (std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '/') {
      cur += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    } else if (!cur.empty()) {
      w.insert(cur);
      cur.clear();
    }
  }
  return w;
}

// The database's lenses closest to maker + model: most shared words (Jaccard), at most n.
std::vector<std::string> ClosestLenses(const lfDatabase& db, const std::string& maker, const std::string& model,
                                       size_t n) {
  const std::set<std::string> q = Words(maker + " " + model);
  std::vector<std::pair<double, std::string>> scored;
  for (const lfLens* const* l = db.GetLenses(); l && *l; ++l) {
    const std::string name = Str((*l)->Maker) + ":" + Str((*l)->Model);
    const std::set<std::string> w = Words(Str((*l)->Maker) + " " + Str((*l)->Model));
    size_t common = 0;
    for (const auto& x : q) common += w.count(x);
    const double score = static_cast<double>(common) / static_cast<double>(q.size() + w.size() - common);
    if (common > 0) scored.push_back({-score, name});
  }
  std::sort(scored.begin(), scored.end());
  std::vector<std::string> out;
  for (const auto& s : scored) {
    if (out.size() >= n) break;
    if (std::find(out.begin(), out.end(), s.second) == out.end()) out.push_back(s.second);
  }
  return out;
}

const lfCamera* FindCamera(const lfDatabase& db, const LensQuery& q) {
  if (q.camera_maker.empty() && q.camera_model.empty()) return nullptr;
  const char* maker = q.camera_maker.empty() ? nullptr : q.camera_maker.c_str();
  const char* model = q.camera_model.empty() ? nullptr : q.camera_model.c_str();
  const lfCamera** cams = db.FindCameras(maker, model);
  if (!cams) cams = db.FindCamerasExt(maker, model, LF_SEARCH_LOOSE);
  // The loose search ranks "E-M1MarkIII" with "E-M1": the model spelt as asked wins.
  const lfCamera* cam = cams ? cams[0] : nullptr;
  for (const lfCamera** c = cams; c && *c; ++c)
    if (Words(Str((*c)->Model)) == Words(q.camera_model)) {
      cam = *c;
      break;
    }
  lf_free(cams);
  return cam;
}

// lensfun's matches for the lens names, best first (with the camera's mount and crop
// factor; without them when that finds nothing: a lens on an adapter, or a camera the
// database lacks).
std::vector<const lfLens*> FindLensCandidates(const lfDatabase& db, const lfCamera* cam, const LensQuery& q) {
  std::vector<const lfLens*> out;
  if (q.lens_model.empty()) return out;
  const char* maker = q.lens_maker.empty() ? nullptr : q.lens_maker.c_str();
  for (const lfCamera* c : {cam, static_cast<const lfCamera*>(nullptr)}) {
    const lfLens** lenses = db.FindLenses(c, maker, q.lens_model.c_str());
    for (const lfLens** l = lenses; l && *l; ++l) out.push_back(*l);
    lf_free(lenses);
    if (!out.empty() || !cam) break;
  }
  return out;
}

const char* LensTypeName(lfLensType t) {
  switch (t) {
    case LF_RECTILINEAR: return "rectilinear";
    case LF_FISHEYE: return "fisheye";
    case LF_PANORAMIC: return "panoramic";
    case LF_EQUIRECTANGULAR: return "equirectangular";
    case LF_FISHEYE_ORTHOGRAPHIC: return "orthographic";
    case LF_FISHEYE_STEREOGRAPHIC: return "stereographic";
    case LF_FISHEYE_EQUISOLID: return "equisolid";
    case LF_FISHEYE_THOBY: return "fisheye_thoby";
    default: return "unknown";
  }
}

std::optional<LensModel> ProjectionOf(lfLensType t) {
  switch (t) {
    case LF_FISHEYE: return LensModel::kEquidistant;  // lensfun's "fisheye" is the equidistant one
    case LF_FISHEYE_EQUISOLID: return LensModel::kEquisolid;
    case LF_FISHEYE_STEREOGRAPHIC: return LensModel::kStereographic;
    default: return std::nullopt;
  }
}

// lensfun's focal length correction for Hugin's models (modifier.cpp get_hugin_focal_correction):
// poly3 and ptlens scale the centre by d = 1 - k1 (1 - a - b - c).
double HuginFocalCorrection(const LensProfile& p) {
  if (!p.distortion_model) return 1.0;
  const auto& t = p.distortion_terms;
  if (*p.distortion_model == "poly3") return 1.0 - t[0];
  if (*p.distortion_model == "ptlens") return 1.0 - t[0] - t[1] - t[2];
  return 1.0;
}

// The calibration at the profile's settings (lfLens::Interpolate*); `missing` says what is not there.
void InterpolateCalibration(const lfLens& lens, LensProfile* p) {
  const float focal = static_cast<float>(p->focal_mm);
  lfLensCalibDistortion d;
  if (lens.InterpolateDistortion(focal, d) && d.Model != LF_DIST_MODEL_NONE) {
    p->distortion_model = d.Model == LF_DIST_MODEL_POLY3 ? "poly3" : d.Model == LF_DIST_MODEL_POLY5 ? "poly5" : "ptlens";
    for (int i = 0; i < 3; ++i) p->distortion_terms[i] = d.Terms[i];
  } else {
    p->missing.push_back("distortion: the profile has no distortion data for this lens");
  }
  lfLensCalibTCA t;
  if (lens.InterpolateTCA(focal, t) && t.Model != LF_TCA_MODEL_NONE) {
    p->tca_model = t.Model == LF_TCA_MODEL_LINEAR ? "linear" : "poly3";
    for (int i = 0; i < 6; ++i) p->tca_terms[i] = t.Terms[i];
  } else {
    p->missing.push_back("tca: the profile has no TCA data for this lens");
  }
  lfLensCalibVignetting v;
  if (!std::isfinite(p->f_number)) {
    p->missing.push_back("vignetting: no f-number (EXIF FNumber) to interpolate the profile at");
  } else if (lens.InterpolateVignetting(focal, static_cast<float>(p->f_number), static_cast<float>(p->distance_m), v) &&
             v.Model == LF_VIGNETTING_MODEL_PA) {
    p->vignetting_k = std::array<double, 3>{v.Terms[0], v.Terms[1], v.Terms[2]};
  } else {
    p->missing.push_back("vignetting: the profile has no vignetting data for this lens at " + FormatNumber(p->focal_mm) +
                         " mm, f/" + FormatNumber(p->f_number));
  }
  lfLensCalibRealFocal rf;
  p->real_focal_mm = lens.InterpolateRealFocal(focal, rf) ? rf.RealFocal : p->focal_mm * HuginFocalCorrection(*p);
}

// The profile of a matched lens at the query's settings.
LensProfile MakeProfile(std::shared_ptr<const lfDatabase> db, const lfCamera* cam, const lfLens* lens,
                        const LensQuery& q) {
  LensProfile p;
  p.query = q;
  if (cam) p.camera_maker = Str(cam->Maker), p.camera_model = Str(cam->Model);
  p.lens_maker = Str(lens->Maker);
  p.lens_model = Str(lens->Model);
  p.lens_type = LensTypeName(lens->Type);
  p.projection = ProjectionOf(lens->Type);
  p.calibration_crop_factor = lens->CropFactor;
  p.calibration_aspect_ratio = lens->AspectRatio;
  p.crop_factor = cam ? cam->CropFactor : lens->CropFactor;
  p.center_offset_x = lens->CenterX;
  p.center_offset_y = lens->CenterY;
  p.f_number = q.f_number;
  p.distance_m = q.distance_m;
  p.focal_mm = q.focal_mm;
  if (lens->MinFocal > 0 && lens->MinFocal == lens->MaxFocal) {  // a prime: its own focal length
    if (std::isfinite(q.focal_mm) && std::abs(q.focal_mm / lens->MinFocal - 1.0) > 0.02)
      p.notes.push_back("focal length: EXIF says " + FormatNumber(q.focal_mm) + " mm, this lens is a " +
                        FormatNumber(lens->MinFocal) + " mm prime; used " + FormatNumber(lens->MinFocal) + " mm");
    p.focal_mm = lens->MinFocal;
  }
  if (!std::isfinite(p.focal_mm)) {
    p.missing.push_back("all: no focal length (EXIF FocalLength) for this zoom lens (" + FormatNumber(lens->MinFocal) +
                        "-" + FormatNumber(lens->MaxFocal) + " mm)");
  } else {
    InterpolateCalibration(*lens, &p);
  }
  auto h = std::make_shared<LensfunHandle>();
  h->db = std::move(db);
  h->lens = lens;
  p.handle = std::move(h);
  return p;
}

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

std::string LensQuery::Describe() const {
  std::string s = "camera " + (camera_maker.empty() && camera_model.empty() ? std::string("(none)")
                                                                              : Quoted(camera_maker) + " " + Quoted(camera_model));
  s += ", lens " + (lens_model.empty() ? std::string("(none)")
                                       : (lens_maker.empty() ? std::string() : Quoted(lens_maker) + " ") + Quoted(lens_model));
  return s;
}

namespace {

std::string TextDatum(const Exiv2::ExifData& exif, const char* key) {
  std::string v = ExifText(exif, key).value_or("");
  while (!v.empty() && (v.back() == '\0' || std::isspace(static_cast<unsigned char>(v.back())))) v.pop_back();
  while (!v.empty() && std::isspace(static_cast<unsigned char>(v.front()))) v.erase(v.begin());
  return v;
}

double NumberDatum(const Exiv2::ExifData& exif, const char* key) {
  const double v = ExifNumber(exif, key);
  return v > 0.0 ? v : NAN;  // 0: the camera's "unknown"
}

}  // namespace

LensQuery ReadLensQuery(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": no such file (reading the EXIF lens names)");
  LensQuery q;
  try {
    auto image = OpenExif(path);
    const Exiv2::ExifData& exif = image->exifData();
    if (exif.empty()) return q;
    q.camera_maker = TextDatum(exif, "Exif.Image.Make");
    q.camera_model = TextDatum(exif, "Exif.Image.Model");
    q.lens_maker = TextDatum(exif, "Exif.Photo.LensMake");
    q.lens_model = TextDatum(exif, "Exif.Photo.LensModel");
    if (q.lens_model.empty()) {  // the maker note's lens (Canon, Nikon, ...), as exiv2 names it
      const auto it = Exiv2::lensName(exif);
      if (it != exif.end()) q.lens_model = it->print(&exif);
    }
    q.focal_mm = NumberDatum(exif, "Exif.Photo.FocalLength");
    q.f_number = NumberDatum(exif, "Exif.Photo.FNumber");
    const double d = NumberDatum(exif, "Exif.Photo.SubjectDistance");
    if (std::isfinite(d) && d < 1000.0) q.distance_m = d;
  } catch (const std::exception&) {
    // Unreadable EXIF (exiv2's errors derive from std::exception): no names; the caller says so.
  }
  return q;
}

void WriteLensQuery(const std::string& path, const LensQuery& q) {
  try {
    auto image = OpenExif(path);
    Exiv2::ExifData exif = image->exifData();
    if (!q.camera_maker.empty()) exif["Exif.Image.Make"] = q.camera_maker;
    if (!q.camera_model.empty()) exif["Exif.Image.Model"] = q.camera_model;
    if (!q.lens_maker.empty()) exif["Exif.Photo.LensMake"] = q.lens_maker;
    if (!q.lens_model.empty()) exif["Exif.Photo.LensModel"] = q.lens_model;
    if (std::isfinite(q.focal_mm))
      exif["Exif.Photo.FocalLength"] = Exiv2::URational(static_cast<uint32_t>(std::lround(q.focal_mm * 1000.0)), 1000u);
    image->setExifData(exif);
    image->writeMetadata();
  } catch (const Exiv2::AnyError& err) {
    throw Error(path + ": cannot write the EXIF lens names (exiv2: " + err.what() + ")");
  }
}

bool ParseLensProfileSpec(const std::string& spec, LensQuery* q, std::string* why) {
  const size_t at = spec.find('@');
  const std::string lens = spec.substr(0, at), camera = at == std::string::npos ? std::string() : spec.substr(at + 1);
  auto split = [&](const std::string& part, const char* what, std::string* maker, std::string* model) {
    const size_t colon = part.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == part.size()) {
      *why = "CaptureOptions::lens_profile = " + spec + ": expected " + what +
             " as MAKER:MODEL (lensfun's names), e.g. 'Samyang:Samyang 8mm f/2.8 UMC Fish-eye@Sony:NEX-7'";
      return false;
    }
    *maker = part.substr(0, colon);
    *model = part.substr(colon + 1);
    return true;
  };
  LensQuery r = *q;
  if (!split(lens, "the lens", &r.lens_maker, &r.lens_model)) return false;
  if (at != std::string::npos && !split(camera, "the camera after '@'", &r.camera_maker, &r.camera_model)) return false;
  r.explicit_spec = true;
  *q = r;
  return true;
}

LensLookup FindLensProfile(const LensQuery& q, const std::string& database_dir) {
  const std::shared_ptr<const lfDatabase> db = LoadDatabase(database_dir);
  LensLookup r;
  const lfCamera* cam = FindCamera(*db, q);
  const std::vector<const lfLens*> lenses = FindLensCandidates(*db, cam, q);
  if (lenses.empty()) {
    std::string found = cam ? "camera found as " + Quoted(Str(cam->Maker)) + " " + Quoted(Str(cam->Model))
                            : (q.camera_model.empty() ? "no camera named" : "no camera matched");
    found += q.lens_model.empty() ? "; no lens named (EXIF LensModel absent)" : "; no lens matched";
    r.message = "lensfun " + std::to_string(LF_VERSION_MAJOR) + "." + std::to_string(LF_VERSION_MINOR) + "." +
                std::to_string(LF_VERSION_MICRO) + ": no lens profile for " + q.Describe() + " (" + found + ")";
    if (!q.lens_model.empty()) r.candidates = ClosestLenses(*db, q.lens_maker, q.lens_model, 3);
    if (!r.candidates.empty()) {
      r.message += "; closest lenses in the database:";
      for (size_t i = 0; i < r.candidates.size(); ++i) r.message += (i ? ", " : " ") + Quoted(r.candidates[i]);
    }
    return r;
  }
  r.profile = MakeProfile(db, cam, lenses[0], q);
  for (size_t i = 1; i < lenses.size() && i < 4; ++i)
    r.profile->other_matches.push_back(Str(lenses[i]->Maker) + ":" + Str(lenses[i]->Model));
  return r;
}

nlohmann::json LensProfile::ToJson() const {
  nlohmann::json j = {{"searched", query.Describe()},
                      {"source", query.explicit_spec ? "CaptureOptions::lens_profile" : "EXIF"},
                      {"lens", lens_maker + ":" + lens_model},
                      {"lens_type", lens_type},
                      {"projection", projection ? nlohmann::json(LensModelName(*projection)) : nlohmann::json()},
                      {"crop_factor", crop_factor},
                      {"calibration_crop_factor", calibration_crop_factor},
                      {"focal_mm", std::isfinite(focal_mm) ? nlohmann::json(focal_mm) : nlohmann::json()},
                      {"real_focal_mm", std::isfinite(real_focal_mm) ? nlohmann::json(real_focal_mm) : nlohmann::json()},
                      {"f_number", std::isfinite(f_number) ? nlohmann::json(f_number) : nlohmann::json()},
                      {"distance_m", distance_m},
                      {"missing", missing}};
  if (!notes.empty()) j["notes"] = notes;
  j["camera"] = camera_model.empty() ? nlohmann::json() : nlohmann::json(camera_maker + ":" + camera_model);
  if (vignetting_k) j["vignetting_pa_k"] = *vignetting_k;
  if (tca_model) j["tca"] = {{"model", *tca_model}, {"terms", tca_terms}};
  if (distortion_model) j["distortion"] = {{"model", *distortion_model}, {"terms", distortion_terms}};
  if (!other_matches.empty()) j["other_matches"] = other_matches;
  return j;
}

namespace {

// lensfun steps x by adding its pixel pitch in float along one call (ApplyColorModification,
// ApplySubpixelGeometryDistortion): restart it every kChunk pixels so the rounding does
// not accumulate across a wide row.
constexpr int kChunk = 64;

// lensfun's modifier for this image at the profile's settings, correcting (reverse =
// false) the corrections in `flags` (LF_MODIFY_*); `done` holds those it will apply.
struct Modifier {
  std::unique_ptr<lfModifier> mod;
  int done = 0;
};

Modifier MakeModifier(const LensProfile& p, int width, int height, int flags) {
  const lfLens* lens = p.handle->lens;
  Modifier m;
  m.mod = std::make_unique<lfModifier>(lens, static_cast<float>(p.crop_factor), width, height);
  const float aperture = std::isfinite(p.f_number) ? static_cast<float>(p.f_number) : 0.0f;
  m.done = m.mod->Initialize(lens, LF_PF_F32, static_cast<float>(p.focal_mm), aperture, static_cast<float>(p.distance_m),
                             1.0f, lens->Type, flags, false);
  return m;
}

void Devignette(const lfModifier& mod, ImageRGB* img, int threads) {
  const int w = img->width;
  ParallelChunks(img->height, ResolveThreads(threads), [&](int y0, int y1, int) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; x += kChunk)
        mod.ApplyColorModification(&img->pixels[img->index(x, y)], static_cast<float>(x), static_cast<float>(y),
                                   std::min(kChunk, w - x), 1, LF_CR_3(RED, GREEN, BLUE), 0);
  });
}

// Each channel resampled where lensfun says the corrected pixel's light fell: one
// ApplySubpixelGeometryDistortion per chunk (x, y of red, green, blue per pixel), then a
// bilinear sample of that channel of the observed image (positions clamped to the image:
// its edge pixels replicated). One copy of the image is the only large allocation.
void RemapChannels(const lfModifier& mod, ImageRGB* img, int threads) {
  const int w = img->width, h = img->height;
  if (w < 2 || h < 2) return;
  const std::vector<float> src = img->pixels;  // the observed image; img receives the corrected one
  const size_t stride = static_cast<size_t>(w) * 3;
  auto sample = [&](float fx, float fy, int c) {
    fx = std::clamp(fx, 0.0f, static_cast<float>(w - 1));
    fy = std::clamp(fy, 0.0f, static_cast<float>(h - 1));
    const int x0 = std::min(static_cast<int>(fx), w - 2), y0 = std::min(static_cast<int>(fy), h - 2);
    const float ax = fx - static_cast<float>(x0), ay = fy - static_cast<float>(y0);
    const float* p = &src[static_cast<size_t>(y0) * stride + static_cast<size_t>(x0) * 3 + c];
    const float top = p[0] + ax * (p[3] - p[0]), bottom = p[stride] + ax * (p[stride + 3] - p[stride]);
    return top + ay * (bottom - top);
  };
  ParallelChunks(h, ResolveThreads(threads), [&](int y0, int y1, int) {
    std::vector<float> coords(static_cast<size_t>(kChunk) * 6);
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; x += kChunk) {
        const int n = std::min(kChunk, w - x);
        mod.ApplySubpixelGeometryDistortion(static_cast<float>(x), static_cast<float>(y), n, 1, coords.data());
        for (int i = 0; i < n; ++i)
          for (int c = 0; c < 3; ++c) {
            float fx = coords[6 * i + 2 * c], fy = coords[6 * i + 2 * c + 1];
            if (!std::isfinite(fx) || !std::isfinite(fy)) fx = static_cast<float>(x + i), fy = static_cast<float>(y);
            img->pixels[img->index(x + i, y) + c] = sample(fx, fy, c);
          }
      }
  });
}

}  // namespace

nlohmann::json ApplyLensProfile(const LensProfile& p, const LensCorrections& which, ImageRGB* img, int threads) {
  nlohmann::json r = {{"vignetting", false}, {"tca", false}, {"distortion", false}};
  if (!p.handle || !std::isfinite(p.focal_mm) || !img || img->empty()) return r;
  const auto t0 = Clock::now();
  if (which.vignetting && p.vignetting_k) {
    const Modifier m = MakeModifier(p, img->width, img->height, LF_MODIFY_VIGNETTING);
    if (m.done & LF_MODIFY_VIGNETTING) {
      Devignette(*m.mod, img, threads);
      r["vignetting"] = true;
    }
  }
  const int flags = (which.tca && p.tca_model ? LF_MODIFY_TCA : 0) |
                    (which.distortion && p.distortion_model ? LF_MODIFY_DISTORTION : 0);
  if (flags) {
    const Modifier m = MakeModifier(p, img->width, img->height, flags);
    if (m.done & (LF_MODIFY_TCA | LF_MODIFY_DISTORTION)) RemapChannels(*m.mod, img, threads);
    r["tca"] = (m.done & LF_MODIFY_TCA) != 0;
    r["distortion"] = (m.done & LF_MODIFY_DISTORTION) != 0;
  }
  r["ms"] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return r;
}

void LensFromProfile(const LensProfile& p, int width, int height, bool distortion_corrected, bool keep_model,
                     bool keep_center, bool keep_radius, bool keep_fov, LensParams* lens, nlohmann::json* report) {
  nlohmann::json& r = *report;
  if (keep_model) {
    r["projection"] = std::string("kept CaptureOptions::lens.model = ") + LensModelName(lens->model) + " (given)";
  } else if (p.projection) {
    lens->model = *p.projection;
    r["projection"] = LensModelName(lens->model);
  } else {
    r["projection"] = "lensfun type '" + p.lens_type + "' has no lens model here; kept CaptureOptions::lens.model = " +
                      LensModelName(lens->model);
  }
  // Pixel-centre extents, as lensfun measures them (modifier.cpp: Width = width - 1).
  const double ew = std::max(width - 1, 1), eh = std::max(height - 1, 1), size = std::min(ew, eh);
  if (!keep_center) {
    lens->center_x = 0.5 * ew + p.center_offset_x * 0.5 * size;
    lens->center_y = 0.5 * eh + p.center_offset_y * 0.5 * size;
    r["center_px"] = {lens->center_x, lens->center_y};
  }
  // The focal length fixes the image circle only through the lens's own projection.
  if (!p.projection || lens->model != *p.projection || !std::isfinite(p.real_focal_mm)) return;
  const double f_mm = p.real_focal_mm / (distortion_corrected ? HuginFocalCorrection(p) : 1.0);
  const double f_px = f_mm * p.crop_factor * 0.5 * std::hypot(ew, eh) / kHalfDiagonal35mm;
  r["focal_px"] = f_px;
  if (keep_radius || !(f_px > 0.0)) return;
  double corner = 0.0;
  for (double cx : {0.0, ew})
    for (double cy : {0.0, eh}) corner = std::max(corner, std::hypot(cx - lens->center_x, cy - lens->center_y));
  double radius = f_px * NormalisedRadius(*lens, 0.5 * lens->fov_deg * M_PI / 180.0);
  if (!(radius <= corner) && !keep_fov) {
    const auto half = AngleFromNormalisedRadius(*lens, corner / f_px);
    if (half) {
      lens->fov_deg = 2.0 * *half * 180.0 / M_PI;
      radius = corner;
      r["fov_deg"] = lens->fov_deg;
      r["fov_note"] = "narrowed to what the image's farthest corner sees (the image circle is larger than the frame)";
    }
  }
  lens->radius_px = radius;
  r["radius_px"] = radius;
}

}  // namespace skycal::capture

#pragma GCC diagnostic pop
