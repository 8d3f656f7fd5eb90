// `skycal batch` through the binary, local engine: a small day (64x32 frames rendered from
// the default preset, file names out of time order) fitted in chunks with warm starts and
// reduced; --resume after a finished batch redoes nothing; a batch killed mid-way (the whole
// process group, SIGKILL) loses no finished frame and --resume completes it; bad input
// (empty glob, mixed sizes, frames without sun direction or time, another batch's --out,
// sbatch missing) exits 1 with a message naming what is wrong and writes nothing.
// The Slurm engine: tests/batch_slurm_test.sh.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <map>
#include <filesystem>
#include <thread>

#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "test_util.h"

namespace skycal {
namespace {
namespace fs = std::filesystem;
using testing::ScratchDir;

testing::ProcessResult Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

// A frame of the default preset at `hour` (sun on an arc: up at 6 h, 60 deg at noon).
void RenderFrame(const std::string& path, double hour, const std::string& size = "64x32", bool with_time = true) {
  const double el = 60.0 * std::sin(M_PI * (hour - 6.0) / 12.0), az = 15.0 * (hour - 12.0);
  const auto r = Skycal("render --backend cpu --size " + size + " --sun-elevation " + std::to_string(el) +
                        " --sun-azimuth " + std::to_string(az) +
                        (with_time ? " --time-of-day " + std::to_string(hour) : std::string()) + " --out " + path);
  ASSERT_EQ(r.rc, 0) << r.err;
}

// `n` frames from 8 h every 2 h, named so that file-name order is the reverse of time order.
void RenderDay(const ScratchDir& dir, int n) {
  fs::create_directories(dir / "day");
  for (int i = 0; i < n; ++i) RenderFrame(dir / ("day/f" + std::to_string(n - 1 - i) + ".exr"), 8.0 + 2.0 * i);
}

std::string BatchArgs(const ScratchDir& dir, const std::string& out) {
  return "batch --references '" + (dir / "day") + "/*.exr' --out " + (dir / out) + " --backend cpu --quiet";
}

TEST(Batch, LocalDayWarmStartsReduceAndResume) {
  ScratchDir dir("batch-local");
  RenderDay(dir, 4);
  const auto r = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --jobs 2 --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json b = nlohmann::json::parse(r.out);
  ASSERT_EQ(b["frames"].size(), 4u);
  // Time order, whatever the names; the second frame of each chunk warm-starts from the first.
  const char* names[] = {"f3", "f2", "f1", "f0"};
  for (int i = 0; i < 4; ++i) {
    const auto& f = b["frames"][i];
    EXPECT_EQ(f["frame"], names[i]);
    EXPECT_DOUBLE_EQ(f["time_of_day_h"].get<double>(), 8.0 + 2.0 * i);
    EXPECT_EQ(f["status"], "ok");
    EXPECT_EQ(f["chunk"], i / 2);
    // The preset's own render: the fit reproduces it (the linear solve's floor, measured ~7e-5).
    EXPECT_LT(f["rel_rmse"].get<double>(), 1e-3) << f;
    // Calibrated (the default frame job): a clear sky, its mask, the game's image against it.
    EXPECT_EQ(f["sky_kind"], "clear") << f;
    EXPECT_LT(f["game_per_pixel_log_rmse"].get<double>(), 0.05) << f;
    EXPECT_TRUE(fs::exists(dir / ("out/frames/" + f["frame"].get<std::string>() + "/render.exr"))) << f;
    if (i % 2 == 0) EXPECT_TRUE(f["warm_start_from"].is_null()) << f;
    else EXPECT_EQ(f["warm_start_from"], names[i - 1]);
  }
  EXPECT_EQ(b["fit_time_s"]["warm_started_frames"], 2);
  EXPECT_EQ(b["run"]["frames_fitted"], 4);
  EXPECT_EQ(b["run"]["exits"].size(), 2u);
  // The reduce: a day fit over every frame, keyframes ordered by time, batch.json on disk.
  EXPECT_EQ(b["day"]["frames"], 4);
  EXPECT_TRUE(fs::exists(dir / "out/day/preset.json"));
  // The day fit read the calibrated photos, each with its own mask.
  EXPECT_EQ(ReadJsonFile(dir / "out/day/fit.json")["options"]["masks"].size(), 4u);
  const nlohmann::json keys = ReadJsonFile(dir / "out/tables/keyframes.json");
  ASSERT_TRUE(keys.contains("keys")) << keys.dump();
  ASSERT_EQ(keys["keys"].size(), 4u);
  EXPECT_EQ(keys["keys"][0]["preset"], "f3");
  EXPECT_DOUBLE_EQ(keys["keys"][3]["time_of_day_h"].get<double>(), 14.0);
  EXPECT_EQ(ReadJsonFile(dir / "out/batch.json")["frames"].size(), 4u);

  // Again without --resume: refused (nothing redone by accident); with it: nothing to fit,
  // every state file untouched.
  const std::string state0 = testing::Slurp(dir / "out/state/f3.json");
  const auto again = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2");
  EXPECT_EQ(again.rc, 1);
  EXPECT_NE(again.err.find("already holds this batch (4 of 4 frames done): pass --resume"), std::string::npos) << again.err;
  const auto resumed = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --resume --json");
  ASSERT_EQ(resumed.rc, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("4 done earlier, 0 chunks to run"), std::string::npos) << resumed.err;
  EXPECT_EQ(nlohmann::json::parse(resumed.out)["run"]["frames_fitted"], 0);
  EXPECT_EQ(testing::Slurp(dir / "out/state/f3.json"), state0);

  // A batch still running there (its lock held, as a running driver or its workers hold it).
  {
    const int fd = ::open((dir / "out/.batch.lock").c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    const auto busy = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --resume");
    ::close(fd);
    EXPECT_EQ(busy.rc, 1);
    EXPECT_NE(busy.err.find("another skycal batch (or the workers of one that was stopped) is still running on it"),
              std::string::npos) << busy.err;
  }

  // Another batch's state: other options, or other frames. Calibrated frames take no fit
  // option but the backend and --quiet.
  const auto calibrate_with_fit_option = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --loss-scale 0.1 --resume");
  EXPECT_EQ(calibrate_with_fit_option.rc, 1);
  EXPECT_NE(calibrate_with_fit_option.err.find("fit options (loss_scale) given with --frame-job calibrate"), std::string::npos)
      << calibrate_with_fit_option.err;
  const auto foreign = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --frame-job fit --loss-scale 0.1 --resume");
  EXPECT_EQ(foreign.rc, 1);
  EXPECT_NE(foreign.err.find("holds another batch's state"), std::string::npos) << foreign.err;
  EXPECT_NE(foreign.err.find("fit_options"), std::string::npos) << foreign.err;
  RenderFrame(dir / "day/extra.exr", 20.0);
  const auto more = Skycal(BatchArgs(dir, "out") + " --frames-per-job 2 --resume");
  EXPECT_EQ(more.rc, 1);
  EXPECT_NE(more.err.find("holds 4 frames, these references are 5"), std::string::npos) << more.err;
  EXPECT_EQ(testing::Slurp(dir / "out/state/f3.json"), state0);
}

TEST(Batch, KilledMidwayLosesNothingAndResumeCompletes) {
  ScratchDir dir("batch-kill");
  RenderDay(dir, 4);
  const std::string args = BatchArgs(dir, "out") + " --frames-per-job 4 --jobs 1";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // its own process group: the driver and its chunk process die together
    ::setpgid(0, 0);
    const std::string cmd = std::string("exec ") + SKYCAL_BINARY + " " + args + " >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  // Kill as soon as the first frame's state is written (polled every 2 ms).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(dir / "out/state/f3.json") && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(-pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(fs::exists(dir / "out/state/f3.json")) << "no frame finished within 120 s";
  int done_before = 0;
  std::map<std::string, std::string> states;
  for (const char* n : {"f3", "f2", "f1", "f0"}) {
    if (fs::exists(dir / ("out/state/" + std::string(n) + ".json"))) {
      ++done_before;
      states[n] = testing::Slurp(dir / ("out/state/" + std::string(n) + ".json"));
    }
  }
  // The kill came mid-way: not every frame is done and nothing was reduced.
  ASSERT_LT(done_before, 4) << "the batch finished before the kill: the test did not test a kill";
  EXPECT_FALSE(fs::exists(dir / "out/batch.json"));

  const auto r = Skycal(args + " --resume --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json b = nlohmann::json::parse(r.out);
  EXPECT_EQ(b["run"]["frames_fitted"], 4 - done_before);
  for (const auto& f : b["frames"]) EXPECT_EQ(f["status"], "ok") << f;
  for (const auto& [n, s] : states) EXPECT_EQ(testing::Slurp(dir / ("out/state/" + n + ".json")), s) << n << " was fitted again";
  // The resumed chunk still warm-starts after the kept frames: the first refitted frame
  // starts from the last frame done before the kill.
  EXPECT_EQ(b["frames"][done_before]["warm_start_from"], b["frames"][done_before - 1]["frame"]);
}

TEST(Batch, BadInputIsRefusedAndWritesNothing) {
  ScratchDir dir("batch-bad");
  auto refused = [&](const std::string& args, const std::string& expected) {
    const auto r = Skycal(args);
    EXPECT_EQ(r.rc, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << args << ": wrote its --out";
  };
  const std::string out = " --out " + (dir / "out") + " --backend cpu";
  refused("batch --references '" + (dir / "none") + "/*.exr'" + out, "matches no file");
  fs::create_directories(dir / "mixed");
  RenderFrame(dir / "mixed/a.exr", 9.0);
  RenderFrame(dir / "mixed/b.exr", 10.0, "128x64");
  refused("batch --references '" + (dir / "mixed") + "/*.exr'" + out, "frames of mixed sizes: ");
  fs::create_directories(dir / "nosun");
  RenderFrame(dir / "nosun/a.exr", 9.0);
  ASSERT_EQ(Skycal("import --in " + (dir / "nosun/a.exr") + " --out " + (dir / "nosun/b.exr")).rc, 0);
  refused("batch --references '" + (dir / "nosun") + "/*.exr'" + out, "1 frame(s) without a sun direction");
  // A sunDirection of another type is named as such (capture::SunDirectionAttribute), not
  // taken for a missing one.
  fs::create_directories(dir / "textsun");
  RenderFrame(dir / "textsun/a.exr", 9.0);
  {
    ExrRGB f = ReadExrRGB(dir / "textsun/a.exr");
    f.attributes.v3fs.erase("sunDirection");
    f.attributes.strings["sunDirection"] = "0 1 0";
    WriteExrRGB(dir / "textsun/a.exr", f.image, f.attributes);
  }
  refused("batch --references '" + (dir / "textsun") + "/*.exr'" + out, "attribute 'sunDirection' is a string \"0 1 0\"");
  fs::create_directories(dir / "notime");
  RenderFrame(dir / "notime/a.exr", 9.0, "64x32", false);
  refused("batch --references '" + (dir / "notime") + "/*.exr'" + out, "without a time of day");
  {
    const auto r = testing::RunSkycal(SKYCAL_BINARY, "batch --references '" + (dir / "mixed") + "/a.exr' --engine slurm" + out,
                                      "PATH=/nonexistent");
    EXPECT_EQ(r.rc, 1);
    EXPECT_NE(r.err.find("--engine slurm: sbatch not found on PATH"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  // A directory that is no batch's.
  fs::create_directories(dir / "other");
  testing::WriteText(dir / "other/notes.txt", "mine");
  const auto r = Skycal("batch --references '" + (dir / "mixed") + "/a.exr' --out " + (dir / "other") + " --backend cpu");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("is not a skycal batch directory"), std::string::npos) << r.err;
  EXPECT_EQ(testing::Slurp(dir / "other/notes.txt"), "mine");
}

}  // namespace
}  // namespace skycal
