#include "skycal/batch/batch_plan.h"

#include <fcntl.h>
#include <glob.h>
#include <sys/file.h>
#include <unistd.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"

namespace skycal::batch {
namespace fs = std::filesystem;
namespace {

constexpr const char* kPlanFile = "batch_plan.json";
constexpr const char* kLockFile = ".batch.lock";
const char* const kHow = "; choose another BatchOptions::out_dir, or delete it yourself if it is yours to delete";

nlohmann::json FrameToJson(const BatchFrame& f) {
  return {{"path", f.path},          {"name", f.name},         {"time_of_day_h", f.time_of_day_h},
          {"sun_direction", f.sun_dir}, {"width", f.width},   {"height", f.height},
          {"size_bytes", f.size_bytes}, {"mtime_ns", f.mtime_ns}};
}

BatchFrame FrameFromJson(const nlohmann::json& j) {
  BatchFrame f;
  f.path = j.at("path").get<std::string>();
  f.name = j.at("name").get<std::string>();
  f.time_of_day_h = j.at("time_of_day_h").get<double>();
  f.sun_dir = j.at("sun_direction").get<std::array<double, 3>>();
  f.width = j.at("width").get<int>();
  f.height = j.at("height").get<int>();
  f.size_bytes = j.at("size_bytes").get<long long>();
  f.mtime_ns = j.at("mtime_ns").get<long long>();
  return f;
}

// What differs between two identities, for the refusal message.
std::string IdentityDifference(const nlohmann::json& have, const nlohmann::json& want) {
  for (auto it = want.begin(); it != want.end(); ++it) {
    if (it.key() == "frames") continue;
    if (!have.contains(it.key()) || have[it.key()] != it.value()) {
      return "'" + it.key() + "' was " + (have.contains(it.key()) ? have[it.key()].dump() : std::string("absent")) +
             ", now " + it.value().dump();
    }
  }
  const auto& a = have.value("frames", nlohmann::json::array());
  const auto& b = want.at("frames");
  if (a.size() != b.size()) {
    return "it holds " + std::to_string(a.size()) + " frames, these references are " + std::to_string(b.size());
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].value("path", "") != b[i].value("path", "")) {
      return "frame " + std::to_string(i) + " was " + a[i].value("path", "?") + ", now " + b[i].value("path", "?");
    }
    if (a[i] != b[i]) return b[i].value("path", "?") + " changed (size or modification time)";
  }
  return "the plan differs";
}

}  // namespace

std::vector<std::string> ExpandReferenceGlob(const std::string& pattern) {
  if (pattern.empty()) throw Error("BatchOptions::references_glob is empty (expected a glob such as 'DIR/*.exr')");
  glob_t g{};
  const int rc = ::glob(pattern.c_str(), 0, nullptr, &g);
  std::vector<std::string> paths;
  if (rc == 0) {
    for (size_t i = 0; i < g.gl_pathc; ++i) paths.emplace_back(g.gl_pathv[i]);
  }
  ::globfree(&g);
  if (rc == GLOB_NOMATCH || paths.empty()) {
    throw Error("BatchOptions::references_glob = '" + pattern +
                "': matches no file (expected lat-long EXR frames; quote the glob so the shell does not expand it)");
  }
  if (rc != 0)
    throw Error("BatchOptions::references_glob = '" + pattern + "': the glob could not be read (a directory is unreadable)");
  std::sort(paths.begin(), paths.end());
  return paths;
}

std::vector<BatchFrame> ScanBatchFrames(const std::vector<std::string>& paths) {
  std::vector<BatchFrame> frames;
  std::vector<std::string> no_sun, no_time;
  for (const std::string& p : paths) {
    const ExrHeaderInfo h = ReadExrHeader(p);
    BatchFrame f;
    f.path = fs::absolute(p).lexically_normal().string();
    f.name = fs::path(p).stem().string();
    f.width = h.width;
    f.height = h.height;
    struct stat st {};
    if (::stat(p.c_str(), &st) != 0) throw Error(p + ": cannot stat the file");
    f.size_bytes = st.st_size;
    f.mtime_ns = static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
    if (const auto sun = capture::SunDirectionAttribute(h.attributes, p)) {
      f.sun_dir = *sun;
    } else {
      no_sun.push_back(p);
    }
    const auto t = h.attributes.floats.find("skycalTimeOfDay");
    if (t == h.attributes.floats.end()) {
      no_time.push_back(p);
    } else {
      if (!(t->second >= 0.0f && t->second < 24.0f)) {
        throw Error(p + ": attribute 'skycalTimeOfDay' = " + FormatNumber(t->second) + ": expected hours in [0, 24)");
      }
      f.time_of_day_h = t->second;
    }
    frames.push_back(f);
  }
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (size_t i = 0; i < v.size() && i < 5; ++i) s += (i ? ", " : "") + v[i];
    if (v.size() > 5) s += " and " + std::to_string(v.size() - 5) + " more";
    return s;
  };
  if (!no_sun.empty()) {
    throw Error(std::to_string(no_sun.size()) + " frame(s) without a sun direction (the EXR attribute 'sunDirection', "
                "a V3f toward the sun, as capture and render write it): " + list(no_sun) +
                "; a batch does not guess the sun per frame: add it (skycal capture given the time and place, or "
                "skycal import detecting the sun) or leave those frames out");
  }
  if (!no_time.empty()) {
    throw Error(std::to_string(no_time.size()) + " frame(s) without a time of day (the EXR attribute 'skycalTimeOfDay', "
                "hours, as capture and render write it when given the time): " + list(no_time) +
                "; a batch orders its frames by time");
  }
  for (const BatchFrame& f : frames) {
    if (f.width != frames[0].width || f.height != frames[0].height) {
      throw Error("frames of mixed sizes: " + frames[0].path + " is " + std::to_string(frames[0].width) + "x" +
                  std::to_string(frames[0].height) + ", " + f.path + " is " + std::to_string(f.width) + "x" +
                  std::to_string(f.height) + " (a day's frames share one size: resample them first)");
    }
  }
  std::map<std::string, std::string> names;
  for (const BatchFrame& f : frames) {
    if (auto [it, fresh] = names.emplace(f.name, f.path); !fresh) {
      throw Error(it->second + " and " + f.path + ": two frames share the name '" + f.name + "' (frames/" + f.name +
                  "/ would collide)");
    }
  }
  std::stable_sort(frames.begin(), frames.end(),
                   [](const BatchFrame& a, const BatchFrame& b) { return a.time_of_day_h < b.time_of_day_h; });
  for (size_t i = 1; i < frames.size(); ++i) {
    if (frames[i].time_of_day_h == frames[i - 1].time_of_day_h) {
      throw Error(frames[i - 1].path + " and " + frames[i].path + ": the same skycalTimeOfDay " +
                  FormatNumber(frames[i].time_of_day_h) + " h (one frame per time: the keyframe table has one key each)");
    }
  }
  return frames;
}

std::vector<std::vector<int>> ChunkFrames(int frames, int per_job) {
  std::vector<std::vector<int>> chunks;
  for (int i = 0; i < frames; ++i) {
    if (i % per_job == 0) chunks.emplace_back();
    chunks.back().push_back(i);
  }
  return chunks;
}

nlohmann::json BatchPlanToJson(const BatchPlan& plan) {
  nlohmann::json frames = nlohmann::json::array();
  for (const BatchFrame& f : plan.frames) frames.push_back(FrameToJson(f));
  return {{"note", "skycal batch: the plan of this directory's batch (README, Batch: a time-lapse day)"},
          {"frames", frames},
          {"chunks", plan.chunks},
          {"argv", plan.argv},
          {"identity", plan.identity}};
}

BatchPlan LoadBatchPlan(const std::string& out_dir) {
  const std::string path = (fs::path(out_dir) / kPlanFile).string();
  const nlohmann::json j = ReadJsonFile(path);
  BatchPlan plan;
  try {
    for (const auto& f : j.at("frames")) plan.frames.push_back(FrameFromJson(f));
    plan.chunks = j.at("chunks").get<std::vector<std::vector<int>>>();
    plan.argv = j.at("argv").get<std::vector<std::string>>();
    plan.identity = j.at("identity");
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": not a batch plan (" + e.what() + ")");
  }
  for (const auto& c : plan.chunks) {
    for (int i : c) {
      if (i < 0 || i >= static_cast<int>(plan.frames.size())) throw Error(path + ": chunk names frame " + std::to_string(i));
    }
  }
  return plan;
}

BatchLock::~BatchLock() {
  if (fd_ >= 0) ::close(fd_);
}

namespace {

BatchLock LockBatchDirectory(const fs::path& dir, const std::string& shown) {
  const std::string path = (dir / kLockFile).string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);  // inherited by the workers on purpose
  if (fd < 0) throw Error(shown + ": cannot create " + path);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    throw Error(shown + ": another skycal batch (or the workers of one that was stopped) is still running on it (" +
                path + " is locked): wait for it, or stop its processes");
  }
  return BatchLock(fd);
}

bool EmptyButLock(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().filename() != kLockFile) return false;
  }
  return true;
}

}  // namespace

BatchLock PrepareBatchDirectory(const std::string& out_dir, const BatchPlan& plan, bool resume) {
  const fs::path dir = fs::absolute(out_dir).lexically_normal();
  const std::string shown = "BatchOptions::out_dir = " + out_dir;
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) throw Error(shown + ": exists and is not a directory");
    if (fs::exists(dir / kPlanFile, ec)) {
      nlohmann::json have;
      try {
        have = ReadJsonFile((dir / kPlanFile).string()).at("identity");
      } catch (const std::exception& e) {
        throw Error(shown + ": its " + kPlanFile + " cannot be read (" + e.what() + "): refusing to write into it" + kHow);
      }
      if (have != plan.identity) {
        throw Error(shown + ": holds another batch's state (" + kPlanFile + ": " + IdentityDifference(have, plan.identity) +
                    "): refusing to mix two batches" + kHow);
      }
      if (!resume) {
        const BatchProgress p = CountBatchProgress(dir.string(), plan);
        throw Error(shown + ": already holds this batch (" + std::to_string(p.done) + " of " + std::to_string(p.total) +
                    " frames done): pass BatchOptions::resume to fit only the missing or failed frames, or choose another "
                    "BatchOptions::out_dir");
      }
    } else if (!EmptyButLock(dir)) {
      throw Error(shown + ": directory exists and is not a skycal batch directory (no " + kPlanFile +
                  "): refusing to write into it" + kHow);
    }
  } else {
    if (!fs::is_directory(dir.parent_path(), ec)) {
      throw Error(shown + ": parent directory '" + dir.parent_path().string() + "' does not exist");
    }
    fs::create_directory(dir, ec);
    if (ec) throw Error(shown + ": cannot create the directory (" + ec.message() + ")");
  }
  BatchLock lock = LockBatchDirectory(dir, shown);
  for (const char* sub : {"state", "frames", "logs"}) {
    fs::create_directories(dir / sub, ec);
    if (ec) throw Error(shown + ": cannot create " + sub + "/ (" + ec.message() + ")");
  }
  WriteJsonFileAtomically((dir / kPlanFile).string(), BatchPlanToJson(plan));
  return lock;
}

std::string FrameStatePath(const std::string& out_dir, const std::string& frame) {
  return (fs::path(out_dir) / "state" / (frame + ".json")).string();
}

std::string FrameFitDir(const std::string& out_dir, const std::string& frame) {
  return (fs::path(out_dir) / "frames" / frame).string();
}

std::optional<nlohmann::json> ReadFrameState(const std::string& out_dir, const std::string& frame) {
  const std::string p = FrameStatePath(out_dir, frame);
  std::error_code ec;
  if (!fs::exists(p, ec)) return std::nullopt;
  try {
    return ReadJsonFile(p);
  } catch (const Error&) {
    return std::nullopt;  // written atomically, so only a foreign edit gets here: redo the frame
  }
}

bool FrameDone(const std::string& out_dir, const std::string& frame) {
  const auto s = ReadFrameState(out_dir, frame);
  std::error_code ec;
  return s && s->value("status", "") == "ok" && fs::exists(fs::path(FrameFitDir(out_dir, frame)) / "preset.json", ec);
}

BatchProgress CountBatchProgress(const std::string& out_dir, const BatchPlan& plan) {
  BatchProgress p;
  p.total = static_cast<int>(plan.frames.size());
  for (const BatchFrame& f : plan.frames) {
    if (FrameDone(out_dir, f.name)) {
      ++p.done;
    } else if (const auto s = ReadFrameState(out_dir, f.name); s && s->value("status", "") == "failed") {
      ++p.failed;
    }
  }
  return p;
}

std::vector<int> PendingChunks(const std::string& out_dir, const BatchPlan& plan) {
  std::vector<int> pending;
  for (size_t c = 0; c < plan.chunks.size(); ++c) {
    for (int i : plan.chunks[c]) {
      if (!FrameDone(out_dir, plan.frames[i].name)) {
        pending.push_back(static_cast<int>(c));
        break;
      }
    }
  }
  return pending;
}

}  // namespace skycal::batch
