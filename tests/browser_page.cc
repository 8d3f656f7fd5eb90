#include "browser_page.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/report/html.h"

namespace skycal::testing {
namespace {

using Clock = std::chrono::steady_clock;

std::string FindChromium() {
  if (const char* env = std::getenv("SKYCAL_CHROMIUM"); env && *env) return env;
  const char* path = std::getenv("PATH");
  std::string p = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= p.size()) {
    const size_t end = p.find(':', start);
    const std::string dir = p.substr(start, end == std::string::npos ? std::string::npos : end - start);
    for (const char* name : {"chromium", "chromium-browser"}) {
      const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
      if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    }
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return "";
}

// One Chromium process and its protocol pipe.
class Browser {
 public:
  Browser(const std::string& binary, const std::string& profile_dir, const std::string& log_path) {
    int to_child[2], from_child[2];
    if (::pipe(to_child) != 0 || ::pipe(from_child) != 0) throw std::runtime_error("pipe failed");
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      // Child: the protocol's descriptors are 3 (commands in) and 4 (replies out).
      const int in = ::fcntl(to_child[0], F_DUPFD, 10), out = ::fcntl(from_child[1], F_DUPFD, 10);
      ::dup2(in, 3);
      ::dup2(out, 4);
      const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (log >= 0) {
        ::dup2(log, 1);
        ::dup2(log, 2);
      }
      for (int fd = 5; fd < 1024; ++fd) ::close(fd);
      // Chromium is not ours to sanitize: the sanitizer build's preloaded runtime and options
      // (scripts/sanitizers/options.sh) stay with the test process.
      for (const char* v : {"LD_PRELOAD", "ASAN_OPTIONS", "LSAN_OPTIONS", "UBSAN_OPTIONS"}) ::unsetenv(v);
      std::vector<std::string> args = {binary, "--headless", "--disable-gpu", "--remote-debugging-pipe",
                                       "--no-first-run", "--no-default-browser-check", "--hide-scrollbars",
                                       "--user-data-dir=" + profile_dir, "--enable-logging=stderr", "about:blank"};
      if (::geteuid() == 0) args.insert(args.begin() + 1, "--no-sandbox");  // Chromium refuses root otherwise
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(binary.c_str(), argv.data());
      ::_exit(127);
    }
    ::close(to_child[0]);
    ::close(from_child[1]);
    write_fd_ = to_child[1];
    read_fd_ = from_child[0];
  }
  ~Browser() {
    if (write_fd_ >= 0) ::close(write_fd_);
    if (read_fd_ >= 0) ::close(read_fd_);
    if (pid_ > 0) {
      int status = 0;
      for (int i = 0; i < 50; ++i) {  // up to 5 s for Browser.close to take effect
        if (::waitpid(pid_, &status, WNOHANG) == pid_) return;
        ::usleep(100000);
      }
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    }
  }

  // Sends a command and waits for its reply (events that arrive meanwhile are kept).
  nlohmann::json Call(const std::string& method, const nlohmann::json& params = nlohmann::json::object(),
                      const std::string& session = "", double timeout_s = 30.0) {
    const int id = ++next_id_;
    nlohmann::json msg = {{"id", id}, {"method", method}, {"params", params}};
    if (!session.empty()) msg["sessionId"] = session;
    const std::string text = msg.dump() + std::string(1, '\0');
    for (size_t off = 0; off < text.size();) {
      const ssize_t n = ::write(write_fd_, text.data() + off, text.size() - off);
      if (n <= 0) throw std::runtime_error("Chromium closed the protocol pipe (" + method + ")");
      off += static_cast<size_t>(n);
    }
    const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
    while (true) {
      const nlohmann::json m = Next(deadline, method);
      if (m.contains("id") && m["id"] == id) {
        if (m.contains("error")) throw std::runtime_error(method + ": " + m["error"].dump());
        return m.value("result", nlohmann::json::object());
      }
      if (m.contains("method")) events.push_back(m);
    }
  }

  // Waits for an event named `method` (already received or to come).
  nlohmann::json WaitEvent(const std::string& method, double timeout_s) {
    for (const auto& e : events)
      if (e["method"] == method) return e;
    const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
    while (true) {
      nlohmann::json m = Next(deadline, method);
      if (!m.contains("method")) continue;
      events.push_back(m);
      if (m["method"] == method) return m;
    }
  }

  std::vector<nlohmann::json> events;

 private:
  nlohmann::json Next(Clock::time_point deadline, const std::string& waiting_for) {
    while (true) {
      const size_t nul = buffer_.find('\0');
      if (nul != std::string::npos) {
        nlohmann::json m = nlohmann::json::parse(buffer_.substr(0, nul));
        buffer_.erase(0, nul + 1);
        return m;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) throw std::runtime_error("Chromium did not answer in time (" + waiting_for + ")");
      pollfd p{read_fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      char chunk[65536];
      const ssize_t n = ::read(read_fd_, chunk, sizeof chunk);
      if (n <= 0) throw std::runtime_error("Chromium closed the protocol pipe (" + waiting_for + ")");
      buffer_.append(chunk, static_cast<size_t>(n));
    }
  }

  pid_t pid_ = -1;
  int write_fd_ = -1, read_fd_ = -1;
  int next_id_ = 0;
  std::string buffer_;
};

std::string Tail(const std::string& path) {
  std::string s;
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
    std::fclose(f);
  }
  return s.size() > 1500 ? s.substr(s.size() - 1500) : s;
}

// What the page's script reports once every image has decoded (or failed to).
constexpr const char* kInspect = R"JS(
Promise.all([...document.images].map(i => i.decode().catch(() => null))).then(() => JSON.stringify({
  w: Math.ceil(document.documentElement.scrollWidth), h: Math.ceil(document.documentElement.scrollHeight),
  images: [...document.images].map(i => { const r = i.getBoundingClientRect();
    return {cls: i.className, alt: i.alt, nw: i.naturalWidth, nh: i.naturalHeight,
            x: r.left + window.scrollX, y: r.top + window.scrollY, w: r.width, h: r.height}; })}))
)JS";

}  // namespace

std::optional<PageReport> LoadPageInChromium(const std::string& html_path, const std::string& profile_dir,
                                             std::string* why, double scale) {
  const std::string binary = FindChromium();
  if (binary.empty()) {
    *why = "chromium is not installed (Debian package `chromium`; scripts/setup.sh installs it)";
    return std::nullopt;
  }
  std::filesystem::create_directories(profile_dir);
  const std::string log = profile_dir + "/chromium.log";
  Browser b(binary, profile_dir, log);
  PageReport rep;
  try {
    rep.browser = b.Call("Browser.getVersion", {}, "", 60.0).value("product", "");
  } catch (const std::exception& e) {
    *why = binary + " cannot run here: " + e.what() + "; its log ends: " + Tail(log);
    return std::nullopt;
  }
  const std::string target = b.Call("Target.createTarget", {{"url", "about:blank"}})["targetId"];
  const std::string session = b.Call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}})["sessionId"];
  for (const char* domain : {"Runtime.enable", "Log.enable", "Page.enable"}) b.Call(domain, {}, session);
  b.Call("Emulation.setDeviceMetricsOverride",
         {{"width", 1400}, {"height", 1000}, {"deviceScaleFactor", 1}, {"mobile", false}}, session);
  const std::string url = "file://" + std::filesystem::absolute(html_path).lexically_normal().string();
  b.Call("Page.navigate", {{"url", url}}, session);
  b.WaitEvent("Page.loadEventFired", 60.0);
  const nlohmann::json eval =
      b.Call("Runtime.evaluate", {{"expression", kInspect}, {"awaitPromise", true}, {"returnByValue", true}}, session, 60.0);
  if (eval.contains("exceptionDetails")) throw std::runtime_error("inspecting the page failed: " + eval.dump());
  const nlohmann::json page = nlohmann::json::parse(eval["result"]["value"].get<std::string>());
  rep.page_width = page["w"];
  rep.page_height = page["h"];
  for (const auto& i : page["images"]) {
    rep.images.push_back({i["cls"], i["alt"], i["nw"], i["nh"], i["x"], i["y"], i["w"], i["h"]});
  }
  const nlohmann::json shot = b.Call(
      "Page.captureScreenshot",
      {{"format", "png"},
       {"captureBeyondViewport", true},
       {"clip", {{"x", 0}, {"y", 0}, {"width", rep.page_width}, {"height", rep.page_height}, {"scale", scale}}}},
      session, 120.0);
  rep.screenshot_scale = scale;
  rep.screenshot_png = report::Base64Decode(shot["data"].get<std::string>());
  // Errors: console.error / console.assert, uncaught exceptions, log entries of level error
  // (failed loads, CSP and parser complaints).
  for (const nlohmann::json& e : b.events) {
    const std::string m = e["method"];
    const nlohmann::json& p = e["params"];
    if (m == "Runtime.consoleAPICalled" && (p["type"] == "error" || p["type"] == "assert")) {
      rep.errors.push_back("console." + p["type"].get<std::string>() + ": " + p["args"].dump());
    } else if (m == "Runtime.exceptionThrown") {
      rep.errors.push_back("exception: " + p["exceptionDetails"].dump());
    } else if (m == "Log.entryAdded" && p["entry"]["level"] == "error") {
      rep.errors.push_back("log: " + p["entry"].value("text", std::string()) + " " + p["entry"].value("url", std::string()));
    }
  }
  try {
    b.Call("Browser.close", {}, "", 10.0);
  } catch (const std::exception&) {
    // The pipe may close before the reply: the destructor reaps (or kills) the process.
  }
  return rep;
}

double InkFraction(const PageReport& page, const PageImage& im) {
  const double s = page.screenshot_scale;
  return InkFraction(page.screenshot_png, im.x * s, im.y * s, im.width * s, im.height * s);
}

double InkFraction(const std::string& png, double x, double y, double width, double height) {
  const cv::Mat img = cv::imdecode(cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<char*>(png.data())),
                                   cv::IMREAD_COLOR);
  if (img.empty()) throw std::runtime_error("the screenshot does not decode");
  const int x0 = std::max(0, static_cast<int>(std::ceil(x))), y0 = std::max(0, static_cast<int>(std::ceil(y)));
  const int x1 = std::min(img.cols, static_cast<int>(std::floor(x + width))),
            y1 = std::min(img.rows, static_cast<int>(std::floor(y + height)));
  if (x1 - x0 < 4 || y1 - y0 < 4) return 0.0;
  // Inset by 2 px: the border drawn around the image is not its content.
  const cv::Mat roi = img(cv::Rect(x0 + 2, y0 + 2, x1 - x0 - 4, y1 - y0 - 4));
  std::map<uint32_t, long long> histogram;
  for (int r = 0; r < roi.rows; ++r) {
    for (int c = 0; c < roi.cols; ++c) {
      const cv::Vec3b v = roi.at<cv::Vec3b>(r, c);
      ++histogram[(v[0] << 16) | (v[1] << 8) | v[2]];
    }
  }
  uint32_t mode = 0;
  long long best = -1;
  for (const auto& [k, n] : histogram) {
    if (n > best) best = n, mode = k;
  }
  const int m0 = (mode >> 16) & 255, m1 = (mode >> 8) & 255, m2 = mode & 255;
  long long ink = 0;
  for (int r = 0; r < roi.rows; ++r) {
    for (int c = 0; c < roi.cols; ++c) {
      const cv::Vec3b v = roi.at<cv::Vec3b>(r, c);
      ink += std::abs(v[0] - m0) > 24 || std::abs(v[1] - m1) > 24 || std::abs(v[2] - m2) > 24;
    }
  }
  return static_cast<double>(ink) / static_cast<double>(roi.total());
}

}  // namespace skycal::testing
