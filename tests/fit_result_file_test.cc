// fit.json's typed module (skycal/fit/fit_result_file.h): the writer and the reader agree
// member by member (doubles exactly), and the reader refuses a schema_version it does not
// know and a file that is not JSON, naming the file.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "skycal/core/error.h"
#include "skycal/fit/fit_result_file.h"
#include "run_binary.h"
#include "test_util.h"

namespace skycal {
namespace {

using fit::FitResultFile;
using testing::ScratchDir;
using testing::WriteText;

std::string ErrorOf(const std::string& path) {
  try {
    fit::ReadFitResultFile(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

fit::LinearStartSingleReport SingleStart(double base) {
  fit::LinearStartSingleReport s;
  s.search_width = 64;
  s.robust_width = 128;
  s.width = 256;
  s.unknowns = 37;
  s.samples = 123456789012LL;
  s.solves = 9;
  s.gauss_newton_steps = 4;
  s.search_time_s = base / 7.0;
  s.robust_time_s = base / 11.0;
  s.final_time_s = base / 13.0;
  s.haziness_g = 0.1 + base;
  s.rel_rmse_least_squares = 1.0 / 3.0;
  s.rel_rmse_robust = 2.0 / 7.0;
  s.residual_sigma_log = 0.017;
  s.loss_scale = 0.05 * base;
  s.loss_scale_floor = 1e-300;
  s.loss_scale_by_sun_distance = {{0.0, 10.0, 0.3}, {10.0, 45.5, 0.2 / 3.0}};
  s.held_non_positive = 2;
  s.cost_per_step = {{64, 12.25}, {128, 3.0 / 17.0}};
  s.time_s = base * 1.5;
  s.render_check = fit::RenderCheckReport{"cpu", 1.0 / 1024.0 / 3.0, 1e-3, 0.042};
  return s;
}

fit::FitReferenceEntry Reference(const std::string& name, double base) {
  fit::FitReferenceEntry r;
  r.name = name;
  r.path = "/data/" + name + ".exr";
  r.rel_rmse = base / 3.0;
  r.log_rmse = base / 7.0;
  r.exposure = 1.0 + base / 9.0;
  r.sun_direction = {0.1, 0.2 / 3.0, -0.9871};
  r.sun_elevation_deg = 19.999999999999996;
  r.sun_source = "option";
  r.observed_lut_rows = {3, 4, 5};
  r.clip_level = 65504.0;
  r.pixels = fit::MaskCounts{8000, 7000, 12, 3, 1, 99};
  return r;
}

FitResultFile FullFile() {
  FitResultFile f;
  f.haziness_g = 0.7654321;
  f.time_s = 12.345678901234;
  f.iterations = 17;
  f.termination = "CONVERGENCE";
  f.backend_device = "cpu (8 threads)";
  f.probe = fit::ProbeReport{2, 0.25, 16, 4096, 3, 0.125, false, 0.18, 0.2, "no sun-facing samples"};
  f.linear_start.single = SingleStart(0.3);
  f.levels = {{128, 64, 8192, 37, 5, 10.5, 1.0 / 3.0, {10.5, 2.0, 1.0 / 3.0}, "CONVERGENCE", 6, 2, 0.75}};
  f.levels[0].render_wall_ms = 12.5;
  f.levels[0].render_gpu_ms = 1.0 / 3.0;
  f.skipped = {{"ground_albedo", "no probe"}};
  f.decisions = {{"below horizon", "not sky", 12.5, "measured: 2 runs", std::nullopt, ""},
                 {"ring 3", "saturated", 0.0, "none: x", -0.0012345678901234567, "a/b runs"}};
  f.unobserved_lut_rows = {{7, 88.25, "no reference"}};
  f.references = {Reference("a", 0.1), Reference("b", 0.2)};
  fit::FitProbeSunEntry sun;
  sun.observable = sun.visible = true;
  sun.illuminance_rgb = {1.0 / 3.0, 2.0, 3.5};
  sun.illuminance_rgb_model = {0.1, 0.2, 0.3};
  sun.fitted_illuminance_rgb_model = {0.11, 0.22, 0.33};
  sun.fraction = 0.875;
  sun.residual = 0.03;
  sun.log_rmse = 0.0421;
  sun.samples = 500;
  sun.sun_facing_samples = 200;
  sun.ground_facing_samples = 100;
  sun.probe = "/data/a.probe.json";
  sun.illuminance_lux = 98765.4321;
  sun.sun_tint_rgb = std::array<double, 3>{1.0, 0.95, 0.9};
  f.references[0].sun = sun;
  f.references[0].images = fit::FitReferenceImages{"fit/a.reference.png", "fit/a.fit.png", "fit/a.error.png"};
  f.references[0].sun_illuminance_at_ground_lux = 1.0 / 7.0;
  f.references[1].cloud_mask = fit::FitCloudMaskEntry{1234, 0.15, 0.5, "estimated: against x"};
  f.warnings = {"w1", "w2"};
  f.options = {{"model", "ffxv"}, {"backend", "cpu"}};
  f.clouds = {{"mode", "off"}, {"fitted", false}};
  f.cloud_stats = {{"parameters", {{"extinction", {{"value", 0.5}}}}}};
  f.time_of_day_h = 14.25;
  fit::FitCalibration c;
  c.photo = "photos/park.exr";
  c.sky_kind = "partly cloudy";
  c.sky_kind_reason = "cloud edges: texture 0.051 >= cloudy_texture 0.01";
  c.sky_share = 0.9 / 7.0;
  c.zenith_sky_share = 0.95 / 7.0;
  c.zenith_blue = 0.55;
  c.texture = 0.051;
  c.point_sources = 2.2e-4;
  c.cloud_share = 0.29;
  c.sun_source = "sky";
  c.sun_uncertainty_deg = 3.49;
  c.mask = "mask.exr";
  c.render = "render.exr";
  c.game_sky_pixels = 51234;
  c.game_per_pixel_log_rmse = 0.6 / 7.0;
  c.game_appearance_error = 0.1 / 3.0;
  c.game_cloud_iou = 2.0 / 3.0;
  c.seconds = 4.25;
  f.calibration = c;
  f.out = "/tmp/fitA";
  return f;
}

TEST(FitResultFile, RoundTripIsExactMemberByMember) {
  ScratchDir s("fit-result-file-roundtrip");
  const FitResultFile written = FullFile();
  fit::WriteFitResultFile(s / "fit.json", written);
  const FitResultFile read = fit::ReadFitResultFile(s / "fit.json");
  EXPECT_EQ(read.schema_version, 1);
  EXPECT_EQ(read.haziness_g, 0.7654321);
  EXPECT_EQ(read.references.size(), 2u);
  EXPECT_EQ(read.references[0].rel_rmse, 0.1 / 3.0);
  EXPECT_EQ(read.references[0].sun_direction[1], 0.2 / 3.0);
  ASSERT_TRUE(read.references[0].sun.has_value());
  EXPECT_EQ(read.references[0].sun->illuminance_rgb[0], 1.0 / 3.0);
  ASSERT_TRUE(read.linear_start.single.has_value());
  EXPECT_FALSE(read.linear_start.day.has_value());
  EXPECT_EQ(read.linear_start.single->loss_scale_floor, 1e-300);
  EXPECT_EQ(read.decisions[1].rel_rmse_change, -0.0012345678901234567);
  EXPECT_FALSE(read.decisions[0].rel_rmse_change.has_value());
  EXPECT_EQ(read.probe->ground_albedo_reason, "no sun-facing samples");
  EXPECT_EQ(read.levels[0].cost_per_iteration[2], 1.0 / 3.0);
  EXPECT_EQ(read.levels[0].render_gpu_ms, 1.0 / 3.0);
  EXPECT_EQ(read.time_of_day_h, 14.25);
  ASSERT_TRUE(read.calibration.has_value());
  EXPECT_EQ(read.calibration->game_per_pixel_log_rmse, 0.6 / 7.0);
  EXPECT_EQ(read.calibration->sun_uncertainty_deg, 3.49);
  EXPECT_TRUE(read == written);  // every member, doubles compared exactly
  // Written again, the same text.
  EXPECT_EQ(fit::FitResultFileJson(read).dump(), fit::FitResultFileJson(written).dump());
}

TEST(FitResultFile, RoundTripOfADayAndOfAbsentSections) {
  ScratchDir s("fit-result-file-day");
  FitResultFile f = FullFile();
  f.probe.reset();
  f.linear_start.single.reset();
  fit::LinearStartDayReport day;
  day.mode = "per_reference_then_joint";
  day.haziness_g = 0.61;
  day.joint_samples = 99;
  day.joint_robust_cost_per_step = {5.0, 4.5, 1.0 / 3.0};
  day.render_check = {"vulkan", 2e-4, 1e-3, 0.5};
  day.references = {{"a", SingleStart(0.1)}, {"b", SingleStart(0.2)}};
  day.time_s = 3.25;
  f.linear_start.day = day;
  f.cloud_stats = nullptr;
  f.time_of_day_h.reset();
  f.references[0].sun.reset();
  f.references[0].images.reset();
  fit::WriteFitResultFile(s / "fit.json", f);
  const nlohmann::json text = nlohmann::json::parse(testing::Slurp(s / "fit.json"));
  EXPECT_TRUE(text.at("probe").is_null());
  EXPECT_FALSE(text.contains("cloud_stats"));
  EXPECT_FALSE(text.contains("time_of_day_h"));
  EXPECT_FALSE(text.at("references")[0].contains("sun"));
  EXPECT_EQ(text.at("schema_version"), 1);
  const FitResultFile read = fit::ReadFitResultFile(s / "fit.json");
  ASSERT_TRUE(read.linear_start.day.has_value());
  EXPECT_EQ(read.linear_start.day->references[1].second.haziness_g, 0.1 + 0.2);
  EXPECT_TRUE(read == f);
}

TEST(FitResultFile, RefusesAnUnknownSchemaVersionNamingFileFieldValueAndExpected) {
  ScratchDir s("fit-result-file-version");
  nlohmann::json j = fit::FitResultFileJson(FullFile());
  j["schema_version"] = 99;
  WriteText(s / "fit.json", j.dump());
  const std::string e = ErrorOf(s / "fit.json");
  EXPECT_NE(e.find(s / "fit.json" + ": field 'schema_version': found 99, expected 1"), std::string::npos) << e;
  j["schema_version"] = "1";
  WriteText(s / "fit.json", j.dump());
  EXPECT_NE(ErrorOf(s / "fit.json").find("field 'schema_version': found \"1\", expected the integer 1"), std::string::npos);
}

TEST(FitResultFile, ReadsAFileWithoutSchemaVersionAsVersion1) {
  ScratchDir s("fit-result-file-old");
  nlohmann::json j = fit::FitResultFileJson(FullFile());
  j.erase("schema_version");
  WriteText(s / "fit.json", j.dump());
  const FitResultFile read = fit::ReadFitResultFile(s / "fit.json");
  EXPECT_EQ(read.schema_version, 1);
  EXPECT_EQ(read.references[1].rel_rmse, 0.2 / 3.0);
}

TEST(FitResultFile, RefusesGarbageAndMissingOrMistypedFieldsNamingTheFile) {
  ScratchDir s("fit-result-file-garbage");
  const std::string full = fit::FitResultFileJson(FullFile()).dump();
  WriteText(s / "truncated.json", full.substr(0, full.size() / 2));
  std::string e = ErrorOf(s / "truncated.json");
  EXPECT_NE(e.find(s / "truncated.json" + ": not valid JSON"), std::string::npos) << e;
  WriteText(s / "garbage.json", "\x01\x02 not json");
  e = ErrorOf(s / "garbage.json");
  EXPECT_NE(e.find(s / "garbage.json" + ": not valid JSON"), std::string::npos) << e;
  WriteText(s / "array.json", "[1, 2]");
  e = ErrorOf(s / "array.json");
  EXPECT_NE(e.find(s / "array.json" + ": expected a JSON object, found array"), std::string::npos) << e;
  nlohmann::json j = nlohmann::json::parse(full);
  j["references"][1].erase("log_rmse");
  WriteText(s / "missing.json", j.dump());
  e = ErrorOf(s / "missing.json");
  EXPECT_NE(e.find(s / "missing.json" + ": field 'references[1].log_rmse': missing"), std::string::npos) << e;
  j["references"][1]["log_rmse"] = "0.1";
  WriteText(s / "typed.json", j.dump());
  e = ErrorOf(s / "typed.json");
  EXPECT_NE(e.find("typed.json: field 'references[1].log_rmse': expected a number, found string"), std::string::npos) << e;
}

}  // namespace
}  // namespace skycal
