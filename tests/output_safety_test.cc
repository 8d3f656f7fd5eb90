// Work is never lost, through the binary: no verb writes over one of its inputs (same
// path, another spelling, a symlink, a preset's LUT), an output directory is replaced only
// when it is the same verb's own earlier output holding nothing else, an interrupted run
// leaves no temporary behind and no partial output (and exits 128 + signal), a dead run's temporaries are
// cleaned by the next run in that directory, and a JSON summary that cannot be written
// is an error.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "run_binary.h"
#include "skycal/core/atomic_output_group.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/interrupt_cleanup.h"
#include "skycal/core/sha256.h"
#include "test_util.h"

extern char** environ;

namespace skycal {
namespace {
namespace fs = std::filesystem;

using testing::ProcessResult;
using testing::ScratchDir;

ProcessResult Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

const std::string kSun = " --sun-elevation 20 --sun-azimuth 30 ";

std::string Render(const ScratchDir& dir, const std::string& name) {
  const ProcessResult r = Skycal("render" + kSun + "--size 64x32 --backend cpu --out " + (dir / name));
  EXPECT_EQ(r.rc, 0) << r.err;
  return dir / name;
}

// Temporary names (interrupt_cleanup.h) left anywhere below `dir`.
std::vector<std::string> Leftovers(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (TemporaryOwnerPid(e.path().filename().string()) > 0) found.push_back(e.path().string());
  }
  return found;
}

// Runs the command; expects exit 1, `needle` in stderr, and every input byte-identical.
void ExpectRefused(const std::string& args, const std::string& needle, const std::vector<std::string>& inputs) {
  std::vector<std::string> before;
  for (const auto& f : inputs) before.push_back(Sha256OfFile(f));
  const ProcessResult r = Skycal(args);
  EXPECT_EQ(r.rc, 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << "expected '" << needle << "' in: " << r.err;
  for (size_t i = 0; i < inputs.size(); ++i) EXPECT_EQ(Sha256OfFile(inputs[i]), before[i]) << inputs[i] << " was modified";
}

TEST(OutputSafety, NoVerbWritesOverItsInput) {
  ScratchDir dir("safety-inputs");
  const std::string sky = Render(dir, "sky.exr");
  const std::string same = " is the same file as ";
  // probe-extract: the photo itself, another spelling of it, a symlink to it, a hard link.
  ExpectRefused("probe-extract --image " + sky + " --out " + sky, same, {sky});
  fs::create_directory(dir.path() / "sub");
  ExpectRefused("probe-extract --image " + sky + " --out " + (dir / "sub/../sky.exr"), same, {sky});
  fs::create_symlink(sky, dir.path() / "link.exr");
  ExpectRefused("probe-extract --image " + sky + " --out " + (dir / "link.exr"), same, {sky});
  fs::create_hard_link(sky, dir.path() / "hard.exr");
  ExpectRefused("import --in " + sky + " --out " + (dir / "hard.exr"), same, {sky});
  ExpectRefused("import --in " + sky + " --out " + sky, same, {sky});
  // render over its preset's JSON or one of its LUTs: the preset would be broken for good.
  ASSERT_EQ(Skycal("bake --out " + (dir / "p.json")).rc, 0);
  const std::vector<std::string> preset = {dir / "p.json", dir / "p.rayleigh.exr", dir / "p.mie.exr",
                                           dir / "p.sun_transmittance.exr"};
  ExpectRefused("render" + kSun + "--preset " + (dir / "p.json") + " --out " + (dir / "p.mie.exr"), "LUT", preset);
  fs::create_symlink(dir / "p.sun_transmittance.exr", dir.path() / "lut.png");
  ExpectRefused("render" + kSun + "--preset " + (dir / "p.json") + " --out " + (dir / "x.exr") + " --png " +
                    (dir / "lut.png"),
                "LUT", preset);
  EXPECT_FALSE(fs::exists(dir.path() / "x.exr"));
  // capture: the rig's camera image.
  testing::WriteText(dir / "rig.json", R"({"format_version": 1, "cameras": [{"name": "up", "image": "sky.exr", "image_size": [64, 32],
      "lens": {"model": "latlong"}, "rotation": {"yaw_deg": 0, "pitch_deg": 0}}]})");
  ExpectRefused("capture --rig " + (dir / "rig.json") + " --size 64x32 --out " + sky, same, {sky, dir / "rig.json"});
  // fit and export: a directory output that an input lives in is never replaced.
  fs::create_directory(dir.path() / "run");
  fs::copy(sky, dir.path() / "run/ref.exr");
  ExpectRefused("fit --quiet --backend cpu --reference " + (dir / "run/ref.exr") + " --out " + (dir / "run"), "holds",
                {dir / "run/ref.exr"});
  ExpectRefused("export --preset " + (dir / "p.json") + " --out " + dir.path().string(), "holds", preset);
  EXPECT_TRUE(Leftovers(dir.path()).empty());
}

TEST(OutputSafety, AnOutputDirectoryIsReplacedOnlyWhenItIsTheVerbsOwn) {
  ScratchDir dir("safety-dirs");
  const std::string sky = Render(dir, "sky.exr");
  const std::string fit = "fit --quiet --backend cpu --reference " + sky + " --out " + (dir / "out");
  ASSERT_EQ(Skycal(fit).rc, 0);
  ASSERT_TRUE(fs::exists(dir.path() / "out/.skycal-output.json"));
  const auto first = fs::last_write_time(dir.path() / "out/fit.json");
  // The verb's own earlier output, untouched: replaced.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const ProcessResult again = Skycal(fit);
  ASSERT_EQ(again.rc, 0) << again.err;
  EXPECT_GT(fs::last_write_time(dir.path() / "out/fit.json"), first);
  // A file the user added: refused, the file kept, the earlier output intact.
  testing::WriteText(dir / "out/notes.txt", "keep me");
  ExpectRefused(fit, "notes.txt", {dir / "out/notes.txt", dir / "out/preset.json"});
  fs::remove(dir.path() / "out/notes.txt");
  // Another verb's output directory: refused.
  ExpectRefused("export --preset " + (dir / "out/preset.json") + " --out " + (dir / "out"), "holds",
                {dir / "out/preset.json"});
  ASSERT_EQ(Skycal("export --preset " + (dir / "out/preset.json") + " --out " + (dir / "game")).rc, 0);
  ExpectRefused(fit.substr(0, fit.find(" --out ")) + " --out " + (dir / "game"), "skycal fit", {dir / "game/manifest.json"});
  // A directory without the marker (not ours, or from before markers existed): refused.
  fs::create_directory(dir.path() / "plain");
  testing::WriteText(dir / "plain/fit.json", "{}");
  ExpectRefused(fit.substr(0, fit.find(" --out ")) + " --out " + (dir / "plain"), ".skycal-output.json",
                {dir / "plain/fit.json"});
  EXPECT_TRUE(Leftovers(dir.path()).empty());
}

// Starts `skycal ARGS...` with stdout and stderr to /dev/null; returns its PID.
pid_t Spawn(const std::vector<std::string>& args) {
  std::vector<std::string> argv_s{SKYCAL_BINARY};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, SKYCAL_BINARY, &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

int ExitCode(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
}

TEST(OutputSafety, InterruptedRunsLeaveNothingBehind) {
  ScratchDir dir("safety-signals");
  const std::string sky = Render(dir, "sky.exr");
  // A large render (about 1 s of CPU work, then a 37 MB EXR) interrupted at several points:
  // during start-up, the render and the write. Either it finished (0) or it stopped with
  // 128 + signal and left neither its output nor a temporary. The points are fractions of
  // an uninterrupted run timed here first (the run's length depends on the machine and its
  // load; fixed delays let a faster build finish before the late ones).
  const std::vector<std::string> big = {"render", "--sun-elevation", "10", "--sun-azimuth", "0", "--size", "4096x2048",
                                        "--backend", "cpu", "--out", dir / "big.exr"};
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(ExitCode(Spawn(big)), 0);
  const double run_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  int interrupted = 0;
  for (double at : {0.0, 0.15, 0.35, 0.55, 0.75, 0.9}) {
    const int delay_ms = at == 0.0 ? 50 : static_cast<int>(at * run_ms);
    for (int sig : {SIGINT, SIGTERM}) {
      const std::string out = dir / "big.exr";
      fs::remove(out);
      const pid_t pid = Spawn(big);
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      kill(pid, sig);
      const int rc = ExitCode(pid);
      std::printf("[measured] signal %d at %d ms (%.0f%% of the run): exit %d, output %s\n", sig, delay_ms,
                  100.0 * delay_ms / run_ms, rc, fs::exists(out) ? "complete" : "none");
      if (rc == 128 + sig) {
        ++interrupted;
        // Nothing, or (a signal after the EXR was moved into place, during the teardown)
        // the whole image: never a part of one.
        if (fs::exists(out)) EXPECT_EQ(ReadExrRGB(out).image.width, 4096) << "interrupted at " << delay_ms << " ms";
      } else if (rc == 1000 + sig) {
        // Killed by the default action: the signal came before main() installed the
        // cleanup (the dynamic loader takes ~0.1 s), when nothing can have been written.
        EXPECT_FALSE(fs::exists(out));
      } else {
        EXPECT_EQ(rc, 0) << "signal " << sig << " at " << delay_ms << " ms";
      }
      EXPECT_TRUE(Leftovers(dir.path()).empty()) << "signal " << sig << " at " << delay_ms << " ms";
    }
  }
  EXPECT_GE(interrupted, 6) << "uninterrupted run " << run_ms << " ms";  // most points fall inside the run, else the test tests nothing
  // A fit (staging directory) interrupted during its solve.
  for (int delay_ms : {150, 400}) {
    const pid_t pid = Spawn({"fit", "--quiet", "--reference", sky, "--out", dir / "fitted"});
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    kill(pid, SIGTERM);
    const int rc = ExitCode(pid);
    EXPECT_TRUE(rc == 128 + SIGTERM || rc == 1000 + SIGTERM || rc == 0) << rc;
    EXPECT_TRUE(Leftovers(dir.path()).empty()) << "fit interrupted at " << delay_ms << " ms";
  }
}

TEST(OutputSafety, TheNextRunRemovesTemporariesOfDeadRunsOnly) {
  ScratchDir dir("safety-stale");
  // A PID that is certainly dead: a child that has exited and been reaped.
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, nullptr, 0);
  const std::string d = std::to_string(dead), alive = std::to_string(getpid());
  testing::WriteText(dir / (".sky.exr.tmp-" + d + "-0"), "partial");
  fs::create_directory(dir.path() / (".fitted.tmp-" + d));
  testing::WriteText(dir / (".fitted.tmp-" + d + "/preset.json"), "partial");
  testing::WriteText(dir / (".other.exr.tmp-" + alive + "-3"), "a live run's");
  testing::WriteText(dir / ".notes.tmp-draft", "not ours: no PID");
  Render(dir, "sky.exr");
  EXPECT_FALSE(fs::exists(dir.path() / (".sky.exr.tmp-" + d + "-0")));
  EXPECT_FALSE(fs::exists(dir.path() / (".fitted.tmp-" + d)));
  EXPECT_TRUE(fs::exists(dir.path() / (".other.exr.tmp-" + alive + "-3")));
  EXPECT_TRUE(fs::exists(dir.path() / ".notes.tmp-draft"));
}

std::string Text(const fs::path& p) {
  std::ifstream f(p);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void Put(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(OutputSafety, AGroupOfFilesIsCommittedTogetherOrNotAtAll) {
  ScratchDir dir("group-commit");
  Put(dir / "a.txt", "old a");
  {  // committed: both new, nothing staged left
    AtomicOutputGroup g;
    const std::string a = g.Add(dir / "a.txt"), b = g.Add(dir / "b.txt");
    EXPECT_EQ(fs::path(a).filename(), "a.txt");
    EXPECT_NE(fs::path(a).parent_path(), dir.path());
    Put(a, "new a");
    Put(b, "new b");
    EXPECT_EQ(Text(dir / "a.txt"), "old a");  // nothing changes before Commit
    EXPECT_FALSE(fs::exists(dir / "b.txt"));
    g.Commit();
  }
  EXPECT_EQ(Text(dir / "a.txt"), "new a");
  EXPECT_EQ(Text(dir / "b.txt"), "new b");
  EXPECT_EQ(Leftovers(dir.path()), std::vector<std::string>{});
  {  // the second rename fails (a directory appeared there): the first file is put back
    AtomicOutputGroup g;
    const std::string a = g.Add(dir / "a.txt"), c = g.Add(dir / "c.txt");
    Put(a, "newer a");
    Put(c, "new c");
    fs::create_directory(dir.path() / "c.txt");
    Put(dir / "c.txt/inside", "x");
    std::string message;
    try {
      g.Commit();
    } catch (const Error& e) {
      message = g.Unstaged(e.what());
    }
    EXPECT_NE(message.find(dir / "c.txt"), std::string::npos) << message;
    EXPECT_NE(message.find("put back"), std::string::npos) << message;
  }
  EXPECT_EQ(Text(dir / "a.txt"), "new a");
  EXPECT_TRUE(fs::is_directory(dir / "c.txt"));
  EXPECT_EQ(Leftovers(dir.path()), std::vector<std::string>{});
  {  // not committed: nothing changes, nothing staged left
    AtomicOutputGroup g;
    Put(g.Add(dir / "a.txt"), "abandoned");
  }
  EXPECT_EQ(Text(dir / "a.txt"), "new a");
  EXPECT_EQ(Leftovers(dir.path()), std::vector<std::string>{});
}

TEST(OutputSafety, TemporaryNamesAreRecognisedExactly) {
  EXPECT_EQ(TemporaryOwnerPid(".sky.exr.tmp-1234-0"), 1234);
  EXPECT_EQ(TemporaryOwnerPid(".fitted.tmp-77"), 77);
  EXPECT_EQ(TemporaryOwnerPid(".fitted.old-77"), 77);
  EXPECT_EQ(TemporaryOwnerPid("sky.exr.tmp-1234-0"), -1);  // not hidden: a user's file
  EXPECT_EQ(TemporaryOwnerPid(".sky.tmp-12x"), -1);
  EXPECT_EQ(TemporaryOwnerPid(".sky.tmp-12-"), -1);
  EXPECT_EQ(TemporaryOwnerPid(".sky.tmp-"), -1);
  EXPECT_EQ(TemporaryOwnerPid(".tmp-12"), -1);
  EXPECT_EQ(TemporaryOwnerPid("..out.tmp-4321-scratch"), 4321);  // bench's scratch
  EXPECT_EQ(TemporaryOwnerPid("..out.tmp-4321-scratchy"), -1);
}

TEST(OutputSafety, AJsonSummaryThatCannotBeWrittenIsAnError) {
  const std::string sun = std::string(SKYCAL_BINARY) + " sun --time 2026-06-21T12:00:00Z --lat 48 --lon 11 --json";
  EXPECT_EQ(WEXITSTATUS(std::system((sun + " >/dev/null 2>&1").c_str())), 0);
  EXPECT_EQ(WEXITSTATUS(std::system((sun + " >/dev/full 2>/dev/null").c_str())), 1);  // disk full
  EXPECT_EQ(WEXITSTATUS(std::system((sun + " >&- 2>/dev/null").c_str())), 1);          // stdout closed
  // A pipe whose reader has gone: SIGPIPE is ignored, the write error reported.
  EXPECT_EQ(WEXITSTATUS(std::system(("bash -c 'set -o pipefail; " + sun + " 2>/dev/null | true'").c_str())), 1);
}

}  // namespace
}  // namespace skycal
