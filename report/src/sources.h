// What a report is made of: the fit, export and bench outputs found under a directory,
// read into typed records (errors name the file and the field).
#pragma once
#include "skycal/fit/fit_result_file.h"
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace skycal::report {

struct ReferenceRecord {
  std::string name;
  double rel_rmse = 0.0, log_rmse = 0.0, exposure = 1.0;
  std::optional<double> sun_elevation_deg;
  std::optional<double> sun_lux_model;   // the fitted preset's sun at the ground (model units)
  std::optional<double> probe_sun_lux;   // the gray probe's sun (--absolute fits)
  std::optional<double> probe_sun_fraction;
  std::optional<bool> probe_sun_visible;
  std::optional<double> cloudy_fraction;  // of the sky pixels, masked as cloud (fit --cloud-mask)
  std::vector<std::pair<std::string, long long>> pixels;  // class -> count
  // Absolute paths of the images to embed (empty when the fit directory has none).
  std::string image_reference, image_fit, image_error;
};

struct DecisionRecord {
  std::string what, why, saved_ms_basis, rel_rmse_change_basis;
  double saved_ms = 0.0;
  std::optional<double> rel_rmse_change;
};

struct CostCurve {
  std::string label;          // "linear start, 256 wide", "Ceres level 512x256"
  std::vector<double> cost;   // per step / iteration
};

struct ParameterRow {
  std::string name, unit, description, value;  // value formatted (one number or R, G, B)
  std::string range;                           // "min – max"
};

struct FitRecord {
  std::string dir;     // absolute
  std::string label;   // relative to the report's root (the root's DisplayName for itself)
  std::string json_path;
  std::optional<double> time_of_day_h;
  double haziness_g = 0.0, time_s = 0.0;
  int iterations = 0;
  std::string termination, model, backend, loss;
  std::vector<ReferenceRecord> references;
  std::vector<DecisionRecord> decisions;
  std::vector<std::pair<std::string, std::string>> skipped;  // block, reason
  std::vector<std::string> warnings;
  std::vector<CostCurve> convergence;
  std::vector<ParameterRow> parameters;  // from preset.json (empty when absent)
  std::string sheet_png;  // report.png, embedded when the per-reference images are absent
  // fit.json's `clouds` object (fit --clouds): the decision, and per cloud-lighting
  // parameter value / initial / unit / held and why; empty when the fit had none.
  struct CloudParameter {
    std::string name, unit, why;
    double value = 0.0, initial = 0.0;
    bool held = false;
  };
  bool clouds_fitted = false;
  std::string clouds_decision;
  std::optional<double> cloud_pixels_log_rmse_initial, cloud_pixels_log_rmse_final;
  std::vector<CloudParameter> cloud_parameters;
  // fit.json's `cloud_stats` (fit --clouds stats: photographs, whose cloud shapes are
  // unknown): its parameters fill cloud_parameters; per reference the panels (reference |
  // the atmosphere where clear, the fitted bins' median cloud radiance where cloud | error)
  // and the whole-sky errors without and with the cloud statistics.
  struct CloudStatsPanel {
    std::string name, image_reference, image_fit, image_error;
    double atmosphere_rel_rmse = 0.0, atmosphere_log_rmse = 0.0, clouds_rel_rmse = 0.0, clouds_log_rmse = 0.0;
  };
  std::vector<CloudStatsPanel> cloud_stats_panels;
  // fit.json's `calibration` (skycal calibrate) and its compare.png (photo | game | error).
  std::optional<fit::FitCalibration> calibration;
  std::string compare_png;
};

struct ExportRecord {
  std::string dir, label, json_path;
  double pre_exposure = 0.0;
  std::vector<std::string> presets;
  std::vector<std::pair<std::string, std::string>> skipped;
  // keyframes.json when present: columns, units (by column), rows (by column, null = empty)
  std::vector<std::string> columns;
  nlohmann::json units = nlohmann::json::object();
  std::vector<nlohmann::json> keys;
};

struct BenchSuiteRecord {
  std::string name, summary, default_case;
  int cases = 0, front = 0;
  bool default_on_front = false;
  double wall_s = 0.0;
  std::string plot_path;  // absolute; empty when the suite has no plot
};

struct BenchRecord {
  std::string dir, label, json_path, machine, commit, date;
  std::vector<BenchSuiteRecord> suites;
  std::string stress_md;  // contents of stress.md when present
};

// calibrate's day.json (the day's wind from timed partly cloudy frames), at the root only.
struct WindRecord {
  std::string json_path;
  double speed_m_s = 0.0, direction_deg = 0.0;
  struct Pair {
    std::string from, to;
    double dt_s = 0.0, iou_moved = 0.0, iou_unmoved = 0.0, iou_own = 0.0;
  };
  std::vector<Pair> pairs;
};

struct Sources {
  std::optional<WindRecord> wind;
  std::vector<FitRecord> fits;  // sorted by time of day when every fit has one, else by path
  std::vector<ExportRecord> exports;
  std::vector<BenchRecord> benches;
  bool empty() const { return fits.empty() && exports.empty() && benches.empty(); }
};

// The name a directory is shown by: its own, or for a verb's staging directory
// (".DIR.tmp-PID") the DIR it will become.
std::string DisplayName(const std::filesystem::path& dir);

// Searches `root` and its subdirectories down to `max_depth` levels (hidden ones, e.g. a
// verb's staging directories, are skipped) for fit.json (skycal fit), manifest.json (skycal
// export) and results.json (skycal bench). Throws skycal::Error naming the file and field on
// a file that is unreadable or lacks what the report needs, and when nothing is found.
Sources FindSources(const std::string& root, int max_depth);

}  // namespace skycal::report
