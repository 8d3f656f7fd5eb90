// Horizon-biased rows (core/row_mapping.h, `skycal resample`): the mapping and its exact
// inverse, the resampling, the file attribute and its bad forms, and the fit of a
// resampled frame against the fit of the frame it came from.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "resample_verb.h"
#include "run_binary.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/row_mapping.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/renderer.h"
#include "skycal/testing/synthetic_sky.h"
#include "test_util.h"

namespace skycal {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<RowMapping> Mappings() {
  RowMapping asymmetric;
  asymmetric.rows = 301;
  asymmetric.b_up = 2.5;
  asymmetric.b_down = 0.0;
  RowMapping steep;
  steep.rows = 1000;
  steep.b_up = 10.0;
  steep.b_down = 6.0;
  return {RowMapping::ForDensities(512, 2.0, 0.25, 0.25), RowMapping::ForDensities(128, 1.5, 1.0, 0.5), asymmetric,
          steep};
}

TEST(RowMapping, InverseIsExactAndTheMapMonotone) {
  for (const RowMapping& m : Mappings()) {
    SCOPED_TRACE(m.ToAttribute());
    double worst_row = 0.0, worst_elevation = 0.0;
    double previous = kPi;
    for (int k = 0; k <= 10 * (m.rows - 1); ++k) {
      const double y = k / 10.0;
      const double e = m.Elevation(y);
      EXPECT_LT(e, previous + (k == 0 ? 1.0 : 0.0)) << "not strictly decreasing at y " << y;
      previous = e;
      worst_row = std::max(worst_row, std::abs(m.Row(e) - y));
    }
    for (int k = 0; k <= 3600; ++k) {
      const double e = -kPi / 2 + kPi * k / 3600.0;
      worst_elevation = std::max(worst_elevation, std::abs(m.Elevation(m.Row(e)) - e));
    }
    EXPECT_LT(worst_row, 1e-12);
    EXPECT_LT(worst_elevation, 1e-12);
    EXPECT_DOUBLE_EQ(m.Elevation(0.0), kPi / 2);
    EXPECT_DOUBLE_EQ(m.Elevation(m.rows - 1.0), -kPi / 2);
    EXPECT_NEAR(m.Elevation(m.HorizonRow()), 0.0, 1e-15);
    // Density is dy/de: against central differences of the inverse (smooth to O(h^2)).
    for (double e_deg : {-80.0, -30.0, -1.0, 1.0, 10.0, 45.0, 80.0}) {
      const double e = e_deg * kPi / 180.0, h = 1e-6;
      const double numeric = -(m.Row(e + h) - m.Row(e - h)) / (2 * h);
      EXPECT_NEAR(m.Density(e), numeric, 1e-6 * numeric) << "elevation " << e_deg;
    }
    // Solid angles: 4 pi over the frame (the bands telescope; 65,000 terms summed in
    // double leave ~1e-12).
    double total = 0.0;
    for (int y = 0; y < m.rows; ++y)
      for (int x = 0; x < 65; ++x) total += m.PixelSolidAngle(x, y, 65);
    EXPECT_NEAR(total, 4 * kPi, 1e-11);
  }
}

TEST(RowMapping, ZeroShapeIsTheUniformConventionAndDensitiesAreAsAsked) {
  RowMapping uniform;
  uniform.rows = 128;
  for (int y = 0; y < 128; ++y) {
    EXPECT_NEAR(uniform.Elevation(y), latlong::Latitude(y, 128), 1e-15);
    EXPECT_NEAR(uniform.PixelSolidAngle(3, y, 256), latlong::PixelSolidAngle(3, y, 256, 128), 1e-15);
  }
  // Forza Horizon 3's: twice the rows per degree at the horizon, a quarter at the poles.
  const int h = 512;
  const RowMapping m = RowMapping::ForDensities(h, 2.0, 0.25, 0.25);
  const double uniform_density = (h - 1) / kPi;
  EXPECT_NEAR(m.Density(0.0) / uniform_density, 2.0, 2.0 / m.rows);  // rows are rounded
  EXPECT_NEAR(m.Density(kPi / 2) / uniform_density, 0.25, 0.25 / m.rows);
  EXPECT_NEAR(m.Density(-kPi / 2) / uniform_density, 0.25, 0.25 / m.rows);
  EXPECT_NEAR(m.HorizonRow(), (m.rows - 1) / 2.0, 1e-12);
  std::cout << "[row_mapping] 512 rows -> " << m.rows << " (" << 100.0 * m.rows / h << "%), b " << m.b_up << "\n";
  EXPECT_LT(m.rows, h);
  EXPECT_GE(UniformHeightCovering(m), static_cast<int>(std::ceil(kPi * m.Density(0.0))) + 1);
  EXPECT_THROW(RowMapping::ForDensities(h, 1.0, 2.0, 0.5), Error);  // zenith denser than horizon
}

TEST(RowMapping, ResamplingAveragesTheBandOfEachRow) {
  // A source linear in the row coordinate: the mean over any band is the value at its
  // middle (in source rows), so every output row is known in closed form.
  const int w = 8, h = 257;
  ImageRGB src(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) src.at(x, y, c) = static_cast<float>(1.0 + 0.01 * y + c + 0.1 * x);
  const RowMapping m = RowMapping::ForDensities(h, 2.0, 0.25, 0.5);
  const ImageRGB out = ResampleToRows(src, m);
  ASSERT_EQ(out.height, m.rows);
  ASSERT_EQ(out.width, w);
  // Source rows 0..127 are sky, 128 the horizon, 129..256 ground: a row reads its own side
  // (extended linearly to the horizon, exact for this source).
  auto clamped_row = [&](double e, double centre) {
    const double lo = centre < 0.0 ? 128.0 : 0.0, hi = centre > 0.0 ? 128.0 : h - 1.0;
    return std::clamp((0.5 - e / kPi) * (h - 1), lo, hi);
  };
  auto source_row = [&](double e) { return clamped_row(e, e); };
  double worst = 0.0;
  for (int y = 0; y < m.rows; ++y) {
    const double c = m.Elevation(y);
    const double mid = 0.5 * (clamped_row(m.Elevation(y - 0.5), c) + clamped_row(m.Elevation(y + 0.5), c));
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.at(x, y, c) - (1.0 + 0.01 * mid + c + 0.1 * x)));
  }
  EXPECT_LT(worst, 2e-6);  // float output of values ~4
  // Control: the point value at the row's own elevation differs from the band mean near
  // the zenith, where a row spans four source rows unevenly: the check can tell them apart.
  const double y1_point = source_row(m.Elevation(1.0));
  EXPECT_GT(std::abs(out.at(0, 1, 0) - (1.0 + 0.01 * y1_point)), 1e-4);
  // A step at the horizon (sky 1, ground 100): no row above the horizon reads ground.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) src.at(x, y, c) = y <= 128 ? 1.0f : 100.0f;
  const ImageRGB step = ResampleToRows(src, m);
  int sky_rows = 0;
  for (int y = 0; y < m.rows; ++y) {
    if (!(m.Elevation(y) > 0.0)) continue;
    ++sky_rows;
    EXPECT_EQ(step.at(3, y, 1), 1.0f) << "row " << y;
  }
  EXPECT_GT(sky_rows, 10);
}

TEST(RowMapping, AttributeRoundTripAndBadForms) {
  const RowMapping m = RowMapping::ForDensities(300, 2.0, 0.25, 0.25);
  const RowMapping back = RowMapping::FromAttribute(m.ToAttribute(), "f.exr");
  EXPECT_EQ(back.rows, m.rows);
  EXPECT_EQ(back.b_up, m.b_up);  // JSON keeps doubles to the last bit
  EXPECT_EQ(back.b_down, m.b_down);
  struct Bad {
    std::string text, expected;
  };
  const std::vector<Bad> bad = {
      {"{rows: 3", "f.exr: attribute 'skycalRowMapping' is not JSON"},
      {"[1, 2]", "expected a JSON object"},
      {R"({"mapping": "horizon-sinh", "version": 1, "b_up": 1, "b_down": 1})", "field 'rows' is missing"},
      {R"({"mapping": "cosine", "version": 1, "rows": 9, "b_up": 1, "b_down": 1})", "field 'mapping': expected \"horizon-sinh\""},
      {R"({"mapping": "horizon-sinh", "version": 2, "rows": 9, "b_up": 1, "b_down": 1})", "field 'version': expected 1"},
      {R"({"mapping": "horizon-sinh", "version": 1, "rows": "9", "b_up": 1, "b_down": 1})", "field 'rows': expected an integer"},
      {R"({"mapping": "horizon-sinh", "version": 1, "rows": 9, "b_up": -1, "b_down": 1})", "field b_up: expected a finite number in [0, 30]"},
      {R"({"mapping": "horizon-sinh", "version": 1, "rows": 2, "b_up": 1, "b_down": 1})", "field rows: expected an integer in [3,"},
      {R"({"mapping": "horizon-sinh", "version": 1, "rows": 9, "b_up": 1, "b_down": null})", "field 'b_down': expected a number"},
  };
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.text);
    try {
      RowMapping::FromAttribute(b.text, "f.exr");
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(b.expected), std::string::npos) << e.what();
    }
  }
}

// The frame and its resampled copy, fitted the same way: the same sky within 0.1%.
struct FitOutcome {
  double rel_rmse_vs_original = 0.0;  // the fitted preset rendered on the original's grid
  double g = 0.0;
  ImageRGB on_original_grid;
};

FitOutcome FitAndRenderOnOriginal(const std::string& path, const fit::Reference& original, render::SkyRenderer& cpu) {
  fit::FitOptions o;
  o.variant = render::ModelVariant::kFfxvIso;
  o.backend = render::Backend::kCpu;
  o.verbose = false;
  const render::Preset truth = synthetic::TruthPreset(o.variant);
  const fit::Reference ref = fit::LoadReference(path, o);
  const fit::FitResult r = fit::FitSky({ref}, synthetic::PerturbedStart(truth, 5, 0.2, 0.05), o, cpu);
  FitOutcome out;
  out.g = r.preset.haziness_g;
  out.on_original_grid = fit::RenderAtReference(original, r.preset, cpu);
  for (float& v : out.on_original_grid.pixels) v = static_cast<float>(v * r.references[0].exposure);
  out.rel_rmse_vs_original = fit::CompareToReference(original, out.on_original_grid).rel_rmse;
  std::cout << "[row_mapping] " << std::filesystem::path(path).filename() << ": " << ref.radiance.width << "x"
            << ref.radiance.height << ", own rel RMSE " << r.references[0].errors.rel_rmse << ", vs the original "
            << out.rel_rmse_vs_original << ", g " << out.g << "\n";
  return out;
}

TEST(RowMapping, AResampledFrameFitsAsTheOriginalDoes) {
  testing::ScratchDir dir("row-mapping-fit");
  const render::Preset truth = synthetic::TruthPreset(render::ModelVariant::kFfxvIso);
  const std::string original_path = dir / "sky.exr";
  // The game frame is a down-sample (Forza Horizon 3's "single down sample"): rows as dense
  // as a 128-row frame's at the horizon x 2, from a 512 x 256 source. Resampling a source
  // no denser than the output interpolates the steep last degrees above the horizon, where
  // the model changes by ~20% per degree: 0.27% between the fits from a 256 x 128 source.
  // Measured here: 0.04% between the fits, g equal to 1e-3.
  synthetic::WriteSyntheticReference(original_path, truth, 25.0, 40.0, 512);
  cli::ResampleOptions ro;
  ro.in = original_path;
  ro.out = dir / "sky_resampled.exr";
  ro.nominal_height = 128;
  const nlohmann::json summary = cli::RunResampleImpl(ro);
  EXPECT_LT(summary["rows"].get<int>(), 128);

  fit::FitOptions lo;
  lo.backend = render::Backend::kCpu;
  const fit::Reference original = fit::LoadReference(original_path, lo);
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  const FitOutcome a = FitAndRenderOnOriginal(original_path, original, *cpu);
  const FitOutcome b = FitAndRenderOnOriginal(ro.out, original, *cpu);
  // Both fitted skies, on the original's pixels: within 0.1% of each other (rel RMSE of one
  // against the other) and of the original itself.
  fit::Reference a_as_ref = original;
  a_as_ref.radiance = a.on_original_grid;
  const double between = fit::CompareToReference(a_as_ref, b.on_original_grid).rel_rmse;
  std::cout << "[row_mapping] fitted skies differ by rel RMSE " << between << ", g " << a.g << " vs " << b.g << "\n";
  EXPECT_LT(between, 1e-3);
  EXPECT_LT(std::abs(b.rel_rmse_vs_original - a.rel_rmse_vs_original), 1e-3);
  EXPECT_NEAR(b.g, a.g, 1e-2);

  // Control: the same rows read through a wrong mapping (uniform rows) are another sky:
  // the truth rendered at those rows is far from the data, at the right ones close.
  fit::FitOptions lo_cpu = lo;
  fit::Reference resampled = fit::LoadReference(ro.out, lo_cpu);
  const double right = fit::CompareToReference(resampled, fit::RenderAtReference(resampled, truth, *cpu)).rel_rmse;
  resampled.row_mapping->b_up = resampled.row_mapping->b_down = 0.0;
  const double wrong = fit::CompareToReference(resampled, fit::RenderAtReference(resampled, truth, *cpu)).rel_rmse;
  std::cout << "[row_mapping] truth at the resampled rows: rel RMSE " << right << ", through uniform rows " << wrong << "\n";
  EXPECT_LT(right, 5e-3);
  EXPECT_GT(wrong, 5e-2);
}

TEST(RowMapping, BadFramesAreRefusedByName) {
  testing::ScratchDir dir("row-mapping-bad");
  ImageRGB img(64, 20);
  for (float& v : img.pixels) v = 1.0f;
  ExrAttributes attrs;
  attrs.envmap_latlong = true;
  attrs.strings[kRowMappingAttribute] = R"({"mapping": "horizon-sinh", "version": 1, "rows": 21, "b_up": 2, "b_down": 2})";
  const std::string wrong_rows = dir / "wrong_rows.exr";
  WriteExrRGB(wrong_rows, img, attrs);
  attrs.strings[kRowMappingAttribute] = R"({"mapping": "horizon-sinh", "version": 1, "rows": 20, "b_up": "2", "b_down": 2})";
  const std::string bad_field = dir / "bad_field.exr";
  WriteExrRGB(bad_field, img, attrs);
  attrs.strings[kRowMappingAttribute] = R"({"mapping": "horizon-sinh", "version": 1, "rows": 20, "b_up": 2, "b_down": 2})";
  attrs.v3fs["sunDirection"] = {0.0f, 1.0f, 1.0f};
  const std::string good = dir / "good.exr";
  WriteExrRGB(good, img, attrs);

  const std::string bin = SKYCAL_BINARY;
  auto r = testing::RunSkycal(bin, "fit --reference " + wrong_rows + " --backend cpu --out " + (dir / "fit1"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find(wrong_rows + ": attribute 'skycalRowMapping': field 'rows' is 21, but the image has 20 rows"),
            std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit1"));
  r = testing::RunSkycal(bin, "fit --reference " + bad_field + " --backend cpu --out " + (dir / "fit2"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find(bad_field + ": attribute 'skycalRowMapping': field 'b_up': expected a number"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit2"));
  // A reader that needs uniform rows names the attribute; resample does not resample twice.
  r = testing::RunSkycal(bin, "mask --reference " + good + " --out " + (dir / "mask.exr"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("has horizon-biased rows"), std::string::npos) << r.err;
  cli::ResampleOptions ro;
  ro.in = good;
  ro.out = dir / "twice.exr";
  try {
    cli::RunResampleImpl(ro);
    ADD_FAILURE() << "resampled a resampled frame";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has horizon-biased rows"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "twice.exr"));
  ro.zenith_density = 3.0;
  std::string why;
  EXPECT_FALSE(ro.IsValid(&why));
  EXPECT_NE(why.find("--zenith-density and --nadir-density: expected at most --horizon-density"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal
