// Reading bracket images (JPEG, PNG, TIFF: camera_image.h; camera RAW through LibRaw, raw_decode.h) and their
// exposure settings (explicit, EXIF, or the RAW file's own metadata).
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "camera_image.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/capture/exif_exposure.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/capture/raw_decode.h"
#include "skycal/core/error.h"

namespace skycal::capture {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

// The exposure a RAW file's metadata gives, in the EXIF reader's form.
ExifExposure RawExposure(const RawMetadata& m) {
  ExifExposure e;
  e.exposure_time_s = m.exposure_time_s;
  e.f_number = m.f_number;
  e.iso = m.iso;
  e.has_exif = true;
  if (std::isnan(m.exposure_time_s)) e.error = "camera RAW metadata without an exposure time (LibRaw)";
  return e;
}

}  // namespace

BracketImage ReadBracketImage(const std::string& path) { return DecodeCameraImage(path); }

std::vector<Bracket> LoadBrackets(const std::vector<std::string>& paths, const std::vector<double>& exposure_times_s,
                                  int threads, nlohmann::json* report) {
  if (!exposure_times_s.empty() && exposure_times_s.size() != paths.size())
    throw Error("exposure times: " + std::to_string(exposure_times_s.size()) + " given for " +
                std::to_string(paths.size()) + " images (one per image, in the same order, or none to use EXIF)");
  const auto t0 = Clock::now();
  std::vector<Bracket> brackets(paths.size());
  // RAW files carry their exposure in LibRaw's metadata (read while decoding).
  std::vector<std::optional<RawMetadata>> raw(paths.size());
  // Decoding dominates loading (PNG/JPEG inflate, RAW demosaic); one image per worker at a time.
  const int workers = ResolveThreads(threads);
  ParallelChunks(static_cast<int>(paths.size()), workers, [&](int b, int e, int) {
    for (int i = b; i < e; ++i) {
      brackets[i].path = paths[i];
      if (IsRawPath(paths[i])) {
        RawImage r = ReadRawImage(paths[i]);
        brackets[i].image = std::move(r.image);
        if (r.has_matrix) brackets[i].camera_to_rec709.assign(r.camera_to_rec709.begin(), r.camera_to_rec709.end());
        raw[i] = std::move(r.metadata);
      } else {
        brackets[i].image = ReadBracketImage(paths[i]);
      }
    }
  });
  const auto t1 = Clock::now();
  nlohmann::json files = nlohmann::json::array();
  for (size_t i = 0; i < paths.size(); ++i) {
    Bracket& b = brackets[i];
    const ExifExposure exif = raw[i] ? RawExposure(*raw[i]) : ReadExifExposure(paths[i]);
    std::string time_source;
    if (!exposure_times_s.empty()) {
      b.exposure_time_s = exposure_times_s[i];
      time_source = "explicit";
      if (!std::isfinite(b.exposure_time_s) || b.exposure_time_s <= 0.0) {
        std::ostringstream s;
        s << paths[i] << ": exposure time " << b.exposure_time_s << " s given; expected a finite time > 0 s";
        throw Error(s.str());
      }
    } else if (std::isfinite(exif.exposure_time_s)) {
      b.exposure_time_s = exif.exposure_time_s;
      time_source = raw[i] ? "raw" : "exif";
    } else {
      throw Error(paths[i] + ": no exposure time: none given explicitly and the file has no EXIF ExposureTime (" +
                  (exif.error.empty() ? std::string("EXIF present without it") : exif.error) +
                  "); pass the times in bracket order");
    }
    b.f_number = exif.f_number;
    b.iso = exif.iso;
    auto opt = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
    files.push_back({{"path", paths[i]},
                     {"width", b.image.width},
                     {"height", b.image.height},
                     {"bits", b.image.bits},
                     {"exposure_time_s", b.exposure_time_s},
                     {"exposure_time_source", time_source},
                     {"exif_exposure_time_s", opt(exif.exposure_time_s)},
                     {"f_number", opt(b.f_number)},
                     {"iso", opt(b.iso)},
                     {"exif_error", exif.error}});
    if (raw[i]) files.back()["raw"] = RawMetadataToJson(*raw[i]);
  }
  const auto t2 = Clock::now();
  if (report) {
    (*report)["files"] = files;
    (*report)["threads"] = workers;
    (*report)["timings_ms"] = {{"decode", Ms(t0, t1)}, {"exif", Ms(t1, t2)}, {"total", Ms(t0, t2)}};
  }
  return brackets;
}

}  // namespace skycal::capture
