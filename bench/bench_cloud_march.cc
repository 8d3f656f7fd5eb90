// The cloud march's run time in one process, the cases interleaved round by round so that
// a loaded machine slows them alike (ratios within a run are what to compare): the Vulkan
// march (lavapipe here) at the game's settings and naive, the double CPU reference at the
// game's settings, each rendering the bundled default_cloudy preset (sun 25 deg) at the
// given size. Prints one line per case (median, min, max ms) and the ratios of the
// issue's targets; with an output path also writes them as JSON. Besides the wall time it
// takes the process's CPU time per render (all threads, lavapipe's included): on a machine
// shared with other jobs that measures the work, where the wall time measures the share of
// the cores the process got.
//
// Usage: bench_cloud_march [ROUNDS (default 5)] [WIDTH (default 512; height = width / 2)] [OUT.json | -] [vulkan]
//   "-": no JSON; "vulkan": the Vulkan cases only (A/B runs of shader variants).
// The lavapipe thread count is Mesa's LP_NUM_THREADS (default: the core count).
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_util.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "src/cloud_scene.h"

namespace {

using namespace skycal;

struct Case {
  std::string name;
  clouds::CloudRenderer* renderer;
  clouds::MarchOptions march;
  std::vector<double> ms;
  std::vector<double> cpu_ms;
};

double ProcessCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

double Ms(const std::function<void()>& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  fn();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const int rounds = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
    const int width = argc > 2 ? std::max(8, std::atoi(argv[2])) : 512;
    const std::string out = argc > 3 && std::string(argv[3]) != "-" ? argv[3] : "";
    const bool vulkan_only = argc > 4 && std::string(argv[4]) == "vulkan";
    const bench::CloudBenchScene scene = bench::LoadDefaultCloudyScene();
    auto vulkan = clouds::CreateVulkanCloudRenderer();
    auto cpu = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
    std::vector<Case> cases = {{"vulkan game", vulkan.get(), clouds::MarchOptions(), {}},
                               {"vulkan naive", vulkan.get(), clouds::MarchOptions::Naive(), {}},
                               {"cpu double game", cpu.get(), clouds::MarchOptions(), {}}};
    if (vulkan_only) cases.pop_back();
    clouds::CloudRenderRequest req;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(25.0, 40.0);
    req.width = width;
    req.height = width / 2;
    for (Case& c : cases) {  // warm-up: pipeline compilation, texture upload
      req.march = c.march;
      c.renderer->Render(scene.View(), req);
    }
    for (int r = 0; r < rounds; ++r) {
      for (Case& c : cases) {
        req.march = c.march;
        const double cpu0 = ProcessCpuMs();
        c.ms.push_back(Ms([&] { c.renderer->Render(scene.View(), req); }));
        c.cpu_ms.push_back(ProcessCpuMs() - cpu0);
      }
      std::fprintf(stderr, "[bench_cloud_march] round %d/%d\n", r + 1, rounds);
    }
    nlohmann::json j;
    j["size"] = std::to_string(req.width) + "x" + std::to_string(req.height);
    j["rounds"] = rounds;
    j["lp_num_threads"] = std::getenv("LP_NUM_THREADS") ? std::getenv("LP_NUM_THREADS") : "default";
    j["machine"] = bench::MachineJson();
    for (const Case& c : cases) {
      const double med = bench::Median(c.ms);
      const double cpu_med = bench::Median(c.cpu_ms);
      std::printf("%-16s %s  median %8.1f ms  min %8.1f  max %8.1f  cpu time median %8.1f ms  (%s)\n", c.name.c_str(),
                  j["size"].get<std::string>().c_str(), med, *std::min_element(c.ms.begin(), c.ms.end()),
                  *std::max_element(c.ms.begin(), c.ms.end()), cpu_med, c.renderer->Describe().c_str());
      j["median_ms"][c.name] = med;
      j["runs_ms"][c.name] = c.ms;
      j["cpu_median_ms"][c.name] = cpu_med;
    }
    const double game = j["median_ms"]["vulkan game"], naive = j["median_ms"]["vulkan naive"];
    const double game_cpu = j["cpu_median_ms"]["vulkan game"], naive_cpu = j["cpu_median_ms"]["vulkan naive"];
    std::printf("naive / game (vulkan): %.2fx wall, %.2fx cpu time\n", naive / game, naive_cpu / game_cpu);
    j["naive_over_game_cpu"] = naive_cpu / game_cpu;
    j["naive_over_game"] = naive / game;
    if (!vulkan_only) {
      const double cpu_game = j["median_ms"]["cpu double game"];
      const double cpu_game_cpu = j["cpu_median_ms"]["cpu double game"];
      std::printf("cpu reference / vulkan (game): %.2fx wall, %.2fx cpu time\n", cpu_game / game, cpu_game_cpu / game_cpu);
      j["cpu_over_vulkan"] = cpu_game / game;
      j["cpu_over_vulkan_cpu"] = cpu_game_cpu / game_cpu;
    }
    if (!out.empty()) std::ofstream(out) << j.dump(2) << "\n";
    return 0;
  } catch (const skycal::Error& e) {
    std::fprintf(stderr, "bench_cloud_march: %s\n", e.what());
    return 1;
  }
}
