// What the fit controller's stages share: the log and the bundled presets. The input list
// of a preset is game_clouds.h's PresetFileInputs; the floor under which a reference is
// refused is core's RequireValidShare (finite_pixels.h).
#pragma once
#include <cstdint>
#include <iostream>
#include <functional>
#include <string>
#include <vector>

#include "skycal/controllers/game_clouds.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/finite_pixels.h"
#include "skycal/core/format_number.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {

// Where this thread's fit progress goes while a fit with FitControllerOptions::log runs
// (installed by ScopedFitLog); null: stderr.
inline thread_local const std::function<void(const std::string&)>* fit_log_sink = nullptr;

// Progress, one line each: the caller's FitControllerOptions::log, else stderr prefixed as
// `skycal fit` always printed it.
inline void FitLog(const std::string& message) {
  if (fit_log_sink && *fit_log_sink) (*fit_log_sink)(message);
  else std::cerr << "[fit] " << message << std::endl;
}

// Installs FitControllerOptions::log for one fit (restoring the previous sink after).
class ScopedFitLog {
 public:
  explicit ScopedFitLog(const std::function<void(const std::string&)>& log) : previous_(fit_log_sink) {
    if (log) fit_log_sink = &log;
  }
  ~ScopedFitLog() { fit_log_sink = previous_; }
  ScopedFitLog(const ScopedFitLog&) = delete;
  ScopedFitLog& operator=(const ScopedFitLog&) = delete;

 private:
  const std::function<void(const std::string&)>* previous_;
};

// The bundled presets (core/data_dir.h): the clear sky the fit starts from and the cloud mask
// compares against, and the cloudy one the cloud statistics start from (game_clouds.h's
// DefaultCloudyPresetPath).
inline std::string DefaultClearPresetPath() { return DataPath("datasets/presets/default_clear.json"); }

// The cloud noise seed every render uses (`skycal render --clouds`; the noise is cached by it).
inline constexpr uint64_t kRenderCloudNoiseSeed = kCloudNoiseSeed;

}  // namespace skycal::controllers
