// Statistics of cloud pixels and the objective built from them (cloud_stats.h,
// cloud_stats_objective.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>

#include <Eigen/Core>

#include "skycal/cloudfit/cloud_stats_objective.h"
#include "shape_noise_covariance.h"
#include "skycal/clouds/composite.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/core/sort_pairs.h"

namespace skycal::cloudfit {
namespace {

double Smoothstep(double lo, double hi, double v) {
  const double t = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

bool Increasing(const std::vector<double>& v) {
  for (size_t i = 1; i < v.size(); ++i)
    if (!(v[i] > v[i - 1])) return false;
  return v.size() >= 2 && std::isfinite(v.front()) && std::isfinite(v.back());
}

int FindBin(const std::vector<double>& edges, double v) {
  if (v < edges.front() || v > edges.back()) return -1;
  const auto it = std::upper_bound(edges.begin(), edges.end(), v);
  return std::min(static_cast<int>(it - edges.begin()) - 1, static_cast<int>(edges.size()) - 2);
}

// Weighted quantile along the interpolated CDF: sample i sits at cumulative weight
// c_i = sum_{j<i} w_j + w_i / 2 (sorted by value); the quantile at q W interpolates linearly
// between neighbouring samples. Continuous in the values and in the weights. `vw` sorted.
double WeightedQuantileOfSorted(const std::vector<std::pair<double, double>>& vw, double total, double q) {
  const double target = q * total;
  double c_prev = 0.0, v_prev = vw.front().first, acc = 0.0;
  bool first = true;
  for (const auto& [v, w] : vw) {
    const double c = acc + 0.5 * w;
    acc += w;
    if (c >= target) {
      if (first || c <= c_prev) return v;
      return v_prev + (v - v_prev) * (target - c_prev) / (c - c_prev);
    }
    c_prev = c;
    v_prev = v;
    first = false;
  }
  return vw.back().first;
}

// Where each pixel of a width x height frame falls for one sun: its elevation bin (per row),
// sun-angle bin and solid angle (-1: outside the bins). The same for every render of a
// statistics fit (one sun, one size), which computes statistics hundreds of times: kept for
// the last few (frame, sun, bins).
struct StatsGeometry {
  int width = 0, height = 0;
  std::array<double, 3> sun{};
  std::vector<double> sun_edges, elevation_edges;
  std::vector<int> elevation_bin;  // per row
  std::vector<int> sun_bin;        // per pixel
  std::vector<double> omega;       // per pixel, sr
};

std::shared_ptr<const StatsGeometry> MakeStatsGeometry(int width, int height, const std::array<double, 3>& sun,
                                                       const CloudStatsOptions& o) {
  auto g = std::make_shared<StatsGeometry>();
  g->width = width;
  g->height = height;
  g->sun = sun;
  g->sun_edges = o.sun_angle_edges_deg;
  g->elevation_edges = o.elevation_edges_deg;
  const double deg = 180.0 / M_PI;
  g->elevation_bin.resize(height);
  g->sun_bin.assign(static_cast<size_t>(width) * height, -1);
  g->omega.assign(static_cast<size_t>(width) * height, 0.0);
  for (int y = 0; y < height; ++y) {
    g->elevation_bin[y] = FindBin(o.elevation_edges_deg, latlong::Latitude(y, height) * deg);
    if (g->elevation_bin[y] < 0) continue;
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      const auto v = latlong::PixelDirection(x, y, width, height);
      const double c = std::clamp(v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2], -1.0, 1.0);
      g->sun_bin[i] = FindBin(o.sun_angle_edges_deg, std::acos(c) * deg);
      g->omega[i] = latlong::PixelSolidAngle(x, y, width, height);
    }
  }
  return g;
}

std::shared_ptr<const StatsGeometry> StatsGeometryFor(int width, int height, const std::array<double, 3>& sun,
                                                      const CloudStatsOptions& o) {
  constexpr size_t kKept = 8;
  static std::mutex mutex;
  static std::vector<std::shared_ptr<const StatsGeometry>> kept;
  auto same = [&](const StatsGeometry& g) {
    return g.width == width && g.height == height && g.sun == sun && g.sun_edges == o.sun_angle_edges_deg &&
           g.elevation_edges == o.elevation_edges_deg;
  };
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& g : kept)
      if (same(*g)) return g;
  }
  auto g = MakeStatsGeometry(width, height, sun, o);
  std::lock_guard<std::mutex> lock(mutex);
  if (kept.size() >= kKept) kept.erase(kept.begin());
  kept.push_back(g);
  return g;
}

}  // namespace

bool CloudStatsOptions::IsValid(std::string* why) const {
  if (!Increasing(sun_angle_edges_deg) || sun_angle_edges_deg.front() < 0.0 || sun_angle_edges_deg.back() > 180.0) {
    *why = "cloud stats: sun_angle_edges_deg must increase within [0, 180] deg (at least 2 edges)";
    return false;
  }
  if (!Increasing(elevation_edges_deg) || elevation_edges_deg.front() < -90.0 || elevation_edges_deg.back() > 90.0) {
    *why = "cloud stats: elevation_edges_deg must increase within [-90, 90] deg (at least 2 edges)";
    return false;
  }
  if (quantiles.empty() || !std::all_of(quantiles.begin(), quantiles.end(), [](double q) { return q > 0.0 && q < 1.0; })) {
    *why = "cloud stats: quantiles must be non-empty, each in (0, 1)";
    return false;
  }
  if (!(0.0 <= thin_lo && thin_lo < thin_hi && thin_hi <= 1.0 && 0.0 <= thick_lo && thick_lo < thick_hi &&
        thick_hi <= 1.0)) {
    *why = "cloud stats: expected 0 <= thin_lo < thin_hi <= 1 and 0 <= thick_lo < thick_hi <= 1 (opacity)";
    return false;
  }
  if (!(empty_bin_log_residual >= 0.0 && empty_bin_log_residual <= 100.0)) {
    *why = "cloud stats: empty_bin_log_residual = " + std::to_string(empty_bin_log_residual) + " (expected [0, 100] log units)";
    return false;
  }
  if (!(min_bin_sr > 0.0 && min_bin_sr < 4.0 * M_PI)) {
    *why = "cloud stats: min_bin_sr = " + std::to_string(min_bin_sr) + " (expected (0, 4 pi) sr)";
    return false;
  }
  if (!(relative_step > 0.0 && relative_step <= 0.1)) {
    *why = "cloud stats: relative_step = " + std::to_string(relative_step) + " (expected (0, 0.1])";
    return false;
  }
  if (max_iterations < 0 || max_iterations > 1000) {
    *why = "cloud stats: max_iterations = " + std::to_string(max_iterations) + " (expected [0, 1000])";
    return false;
  }
  if (render_width < 8 || render_height < 4 || render_width > 4096 || render_height > 2048) {
    *why = "cloud stats: render size " + std::to_string(render_width) + "x" + std::to_string(render_height) +
           " (expected 8x4 ... 4096x2048 pixels)";
    return false;
  }
  if (model_renders < 1 || model_renders > 64) {
    *why = "cloud stats: model_renders = " + std::to_string(model_renders) + " (expected an integer in [1, 64])";
    return false;
  }
  if (!(std::isfinite(model_time_step_s) && std::abs(model_time_step_s) <= 1e6)) {
    *why = "cloud stats: model_time_step_s = " + std::to_string(model_time_step_s) + " (expected |s| <= 1e6)";
    return false;
  }
  if (!(opacity_share_weight >= 0.0 && opacity_share_weight <= 1e3)) {
    *why = "cloud stats: opacity_share_weight = " + std::to_string(opacity_share_weight) + " (expected [0, 1000])";
    return false;
  }
  if (noise_draws < 0 || noise_draws > 256 || (noise_draws > 0 && noise_draws < 4)) {
    *why = "cloud stats: noise_draws = " + std::to_string(noise_draws) + " (expected 0 (off) or an integer in [4, 256])";
    return false;
  }
  if (!(noise_sd_floor > 0.0 && noise_sd_floor <= 10.0)) {
    *why = "cloud stats: noise_sd_floor = " + std::to_string(noise_sd_floor) + " (expected (0, 10] log radiance)";
    return false;
  }
  if (noise_covariance != "diagonal" && noise_covariance != "full") {
    *why = "cloud stats: noise_covariance = '" + noise_covariance + "' (expected diagonal or full)";
    return false;
  }
  if (!(noise_shrinkage == -1.0 || (noise_shrinkage >= 0.0 && noise_shrinkage <= 1.0))) {
    *why = "cloud stats: noise_shrinkage = " + std::to_string(noise_shrinkage) +
           " (expected a fixed shrinkage in [0, 1], or -1: estimated from the draws)";
    return false;
  }
  if (fitted.empty()) {
    *why = "cloud stats: no parameter to fit (fitted is empty)";
    return false;
  }
  return march.IsValid(why);
}

bool FindCloudBin(const CloudStatsOptions& o, double sun_angle_deg, double elevation_deg, int* sun_bin,
                  int* elevation_bin) {
  *sun_bin = FindBin(o.sun_angle_edges_deg, sun_angle_deg);
  *elevation_bin = FindBin(o.elevation_edges_deg, elevation_deg);
  return *sun_bin >= 0 && *elevation_bin >= 0;
}

void OpacityClassWeights(const CloudStatsOptions& o, double a, double* thin, double* thick) {
  *thick = Smoothstep(o.thick_lo, o.thick_hi, a);
  *thin = Smoothstep(o.thin_lo, o.thin_hi, a) * (1.0 - *thick);
}

CloudStatistics ComputeCloudStatistics(const ImageRGB& img, const std::vector<float>& opacity,
                                       const std::vector<float>& sky, const std::array<double, 3>& sun,
                                       const CloudStatsOptions& o) {
  return ComputeCloudStatistics(std::vector<const ImageRGB*>{&img}, std::vector<const std::vector<float>*>{&opacity}, sky,
                                sun, o);
}

namespace {

// Per (bin, channel): each cloud pixel's (ln radiance, solid angle x opacity-class weight).
using BinSamples = std::vector<std::vector<std::pair<double, double>>>;

// One row's cloud pixels into `samples`, in the order of the serial loop over x.
void GatherRow(const ImageRGB& img, const std::vector<float>& opacity, const std::vector<float>& sky,
               const StatsGeometry& geometry, int y, const CloudStatsOptions& o, const CloudStatistics& s,
               BinSamples* samples) {
  const int eb = geometry.elevation_bin[y];
  for (int x = 0; x < img.width; ++x) {
    const size_t i = static_cast<size_t>(y) * img.width + x;
    if (!sky.empty() && !(sky[i] >= 0.5f)) continue;
    double thin = 0.0, thick = 0.0;
    OpacityClassWeights(o, opacity[i], &thin, &thick);
    if (thick <= 0.0 && thin <= 0.0) continue;
    const float r = img.pixels[3 * i], g = img.pixels[3 * i + 1], b = img.pixels[3 * i + 2];
    if (!(r > 0.0f && g > 0.0f && b > 0.0f && std::isfinite(r) && std::isfinite(g) && std::isfinite(b))) continue;
    const int sb = geometry.sun_bin[i];
    if (sb < 0) continue;
    const double class_weight[2] = {thin, thick};
    for (int k = 0; k < 2; ++k) {
      if (class_weight[k] <= 0.0) continue;
      const int bin = s.Bin(sb, eb, k);
      const double w = geometry.omega[i] * class_weight[k];
      for (int ch = 0; ch < 3; ++ch)
        (*samples)[static_cast<size_t>(bin) * 3 + ch].emplace_back(std::log(img.pixels[3 * i + ch]), w);
    }
  }
}

// A statistics fit computes these for every evaluation (hundreds of times over a few renders),
// the GPU idle meanwhile: rows are gathered and bins sorted on up to this many threads.
constexpr int kStatsThreads = 4;

}  // namespace

CloudStatistics ComputeCloudStatistics(const std::vector<const ImageRGB*>& images,
                                       const std::vector<const std::vector<float>*>& opacities,
                                       const std::vector<float>& sky, const std::array<double, 3>& sun,
                                       const CloudStatsOptions& o) {
  if (images.empty() || images.size() != opacities.size()) throw Error("cloud stats: expected one opacity per image");
  CloudStatistics s;
  s.sun_bins = static_cast<int>(o.sun_angle_edges_deg.size()) - 1;
  s.elevation_bins = static_cast<int>(o.elevation_edges_deg.size()) - 1;
  const int bins = s.sun_bins * s.elevation_bins * CloudStatistics::kOpacityClasses;
  const int nq = static_cast<int>(o.quantiles.size());
  s.weight.assign(bins, 0.0);
  s.log_quantile.assign(static_cast<size_t>(bins) * 3 * nq, 0.0);
  s.thick_share.assign(static_cast<size_t>(s.sun_bins) * s.elevation_bins, 0.0);
  std::vector<std::shared_ptr<const StatsGeometry>> geometry;
  std::vector<std::pair<size_t, int>> rows;  // (image, row) in the serial loop's order
  for (size_t image = 0; image < images.size(); ++image) {
    const ImageRGB& img = *images[image];
    const size_t n = static_cast<size_t>(img.width) * img.height;
    if (opacities[image]->size() != n || (!sky.empty() && sky.size() != n))
      throw Error("cloud stats: the opacity (" + std::to_string(opacities[image]->size()) + ") and sky mask (" +
                  std::to_string(sky.size()) + ") must have one value per pixel of the " + std::to_string(img.width) +
                  "x" + std::to_string(img.height) + " image");
    geometry.push_back(StatsGeometryFor(img.width, img.height, sun, o));
    for (int y = 0; y < img.height; ++y)
      if (geometry.back()->elevation_bin[y] >= 0) rows.emplace_back(image, y);
  }
  // Each worker gathers a contiguous run of rows; concatenated in worker order, every bin's
  // samples (and so the weights summed from them) are the serial loop's, bit for bit.
  const int workers = std::max(1, std::min({ResolveThreads(0), kStatsThreads, static_cast<int>(rows.size())}));
  std::vector<BinSamples> parts(workers, BinSamples(static_cast<size_t>(bins) * 3));
  ParallelChunks(static_cast<int>(rows.size()), workers, [&](int begin, int end, int w) {
    for (int r = begin; r < end; ++r) {
      const auto [image, y] = rows[r];
      GatherRow(*images[image], *opacities[image], sky, *geometry[image], y, o, s, &parts[w]);
    }
  });
  BinSamples samples = std::move(parts[0]);
  for (int w = 1; w < workers; ++w)
    for (size_t k = 0; k < samples.size(); ++k) samples[k].insert(samples[k].end(), parts[w][k].begin(), parts[w][k].end());
  for (int bin = 0; bin < bins; ++bin)
    for (const auto& p : samples[static_cast<size_t>(bin) * 3]) s.weight[bin] += p.second;
  for (int sb = 0; sb < s.sun_bins; ++sb)
    for (int eb = 0; eb < s.elevation_bins; ++eb) {
      const double thin = s.weight[s.Bin(sb, eb, 0)], thick = s.weight[s.Bin(sb, eb, 1)];
      s.thick_share[static_cast<size_t>(sb) * s.elevation_bins + eb] = thin + thick > 0.0 ? thick / (thin + thick) : 0.0;
    }
  ParallelChunks(bins * 3, workers, [&](int begin, int end, int) {
    for (int k = begin; k < end; ++k) {
      auto& vw = samples[k];
      if (vw.empty()) continue;
      SortPairs(&vw);
      double total = 0.0;
      for (const auto& p : vw) total += p.second;
      for (int q = 0; q < nq; ++q) s.log_quantile[static_cast<size_t>(k) * nq + q] = WeightedQuantileOfSorted(vw, total, o.quantiles[q]);
    }
  });
  return s;
}

CloudStatsRender RenderForCloudStats(const CloudStatsReference& ref, const CloudStatsScene& scene,
                                     const clouds::CloudParams& params, clouds::CloudRenderer& renderer,
                                     const CloudStatsOptions& o, double time_offset_s,
                                     const clouds::WeatherMap* weather) {
  if (ref.clear_sky.width != o.render_width || ref.clear_sky.height != o.render_height)
    throw Error("cloud stats: reference '" + ref.name + "': the clear sky is " + std::to_string(ref.clear_sky.width) +
                "x" + std::to_string(ref.clear_sky.height) + ", expected the render size " +
                std::to_string(o.render_width) + "x" + std::to_string(o.render_height));
  clouds::CloudScene cs{scene.preset, &params, scene.noise, weather ? weather : scene.weather};
  clouds::CloudRenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = o.render_width;
  req.height = o.render_height;
  req.time_s = ref.cloud_time_s + time_offset_s;
  req.march = o.march;
  const clouds::CloudImage clouds_img = renderer.Render(cs, req);
  CloudStatsRender out;
  out.composite = clouds::CompositeClouds(ref.clear_sky, clouds_img);
  out.opacity.resize(clouds_img.transmittance.size());
  for (size_t i = 0; i < out.opacity.size(); ++i) out.opacity[i] = 1.0f - clouds_img.transmittance[i];
  return out;
}

CloudStatsObjective::CloudStatsObjective(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                                         clouds::CloudRenderer& renderer, const CloudStatsOptions& options)
    : refs_(refs), scene_(scene), renderer_(renderer), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(why);
  if (!scene.preset || !scene.noise || !scene.weather) throw Error("cloud stats: the scene needs a preset, noise and a weather map");
  for (const clouds::WeatherMap* w : scene.weather_ensemble)
    if (!w) throw Error("cloud stats: a null weather map in the scene's weather_ensemble");
  if (refs.empty()) throw Error("cloud stats: no reference");
  clouds::ValidateCloudParams(scene.initial, "cloud stats: initial parameters");
  clouds::CloudParams init = scene.initial;
  for (const std::string& name : options.fitted) {
    const auto& specs = clouds::CloudParameterSpecs();
    const auto it = std::find_if(specs.begin(), specs.end(), [&](const auto& s) { return name == s.name; });
    if (it == specs.end() || it->kind != clouds::CloudParamSpec::kReal)
      throw Error("cloud stats: fitted parameter 'clouds." + name + "' is not a real-valued cloud field");
    const double v = *it->field(init);
    free_.push_back({name, it->field, it->min, it->max, std::max(std::abs(v), 1e-3 * (it->max - it->min))});
  }
  for (const auto& r : refs) {
    ref_stats_.push_back(ComputeCloudStatistics(r.radiance, r.opacity, r.sky, r.sun_dir, options));
    std::vector<int> active;
    for (int b = 0; b < static_cast<int>(ref_stats_.back().weight.size()); ++b)
      if (ref_stats_.back().weight[b] >= options.min_bin_sr) active.push_back(b);
    if (active.empty())
      throw Error("cloud stats: reference '" + r.name + "' has no bin with at least " +
                  std::to_string(options.min_bin_sr) + " sr of cloud (no cloud pixels to fit)");
    num_residuals_ += static_cast<int>(active.size()) * 3 * static_cast<int>(options.quantiles.size());
    active_bins_.push_back(std::move(active));
    std::vector<int> shares;
    const CloudStatistics& st = ref_stats_.back();
    for (int sb = 0; sb < st.sun_bins; ++sb)
      for (int eb = 0; eb < st.elevation_bins; ++eb)
        if (options.opacity_share_weight > 0.0 && st.weight[st.Bin(sb, eb, 0)] + st.weight[st.Bin(sb, eb, 1)] >= options.min_bin_sr)
          shares.push_back(sb * st.elevation_bins + eb);
    num_residuals_ += static_cast<int>(shares.size());
    active_shares_.push_back(std::move(shares));
  }
  for (const clouds::WeatherMap* w : scene.shape_draw_maps)
    if (!w) throw Error("cloud stats: a null weather map in the scene's shape_draw_maps");
  for (const clouds::CloudNoise* nz : scene.noise_textures)
    if (!nz) throw Error("cloud stats: a null noise texture in the scene's noise_textures");
  ref_values_.assign(num_residuals_, 0.0);
  weights_.assign(num_residuals_, 0.0);
  const int nq = static_cast<int>(options.quantiles.size());
  for (size_t r = 0; r < refs.size(); ++r) {
    offsets_.push_back(r == 0 ? 0
                              : offsets_.back() + static_cast<int>(active_bins_[r - 1].size()) * 3 * nq +
                                    static_cast<int>(active_shares_[r - 1].size()));
    const CloudStatistics& ref = ref_stats_[r];
    Flatten(static_cast<int>(r), ref, 1, ref_values_.data() + offsets_[r]);
    // Each bin counts by its share of the reference's cloud (sqrt: residuals are squared).
    const double total = std::accumulate(ref.weight.begin(), ref.weight.end(), 0.0);
    int k = offsets_[r];
    for (int bin : active_bins_[r])
      for (int j = 0; j < 3 * nq; ++j) weights_[k++] = std::sqrt(ref.weight[bin] / total);
    for (int b : active_shares_[r]) {
      const int sb = b / ref.elevation_bins, eb = b % ref.elevation_bins;
      weights_[k++] = options.opacity_share_weight *
                      std::sqrt((ref.weight[ref.Bin(sb, eb, 0)] + ref.weight[ref.Bin(sb, eb, 1)]) / total);
    }
  }
  for (const clouds::CloudNoise* nz : scene.shape_draw_noises)
    if (!nz) throw Error("cloud stats: a null noise texture in the scene's shape_draw_noises");
  if (options.noise_draws > 0) {
    const std::vector<double> x = InitialX();
    const std::vector<std::vector<double>> draws = NoiseDraws(x.data(), options.noise_draws);
    if (options.noise_covariance == "full")
      SetNoiseCovariance(draws, options.noise_shrinkage);
    else
      SetNoiseSd(NoiseSd(draws));
  }
}

void CloudStatsObjective::Flatten(int r, const CloudStatistics& s, int images, double* values) const {
  const int nq = static_cast<int>(options_.quantiles.size());
  int k = 0;
  for (int bin : active_bins_[r]) {
    // A bin the render leaves (almost) empty has no quantiles to compare.
    const bool present = s.weight[bin] >= 0.5 * options_.min_bin_sr * images;
    for (int ch = 0; ch < 3; ++ch)
      for (int q = 0; q < nq; ++q)
        values[k++] = present ? s.log_quantile[(static_cast<size_t>(bin) * 3 + ch) * nq + q]
                              : std::numeric_limits<double>::quiet_NaN();
  }
  for (int b : active_shares_[r]) values[k++] = s.thick_share[b];
}

void CloudStatsObjective::SetNoiseSd(const std::vector<double>& sd) {
  if (static_cast<int>(sd.size()) != num_residuals_)
    throw Error("cloud stats: " + std::to_string(sd.size()) + " noise sd values for " + std::to_string(num_residuals_) +
                " statistics");
  noise_sd_.resize(sd.size());
  const double pooled = std::sqrt(1.0 + 1.0 / options_.model_renders);
  for (size_t k = 0; k < sd.size(); ++k) {
    noise_sd_[k] = std::max(std::isfinite(sd[k]) ? sd[k] : kAbsentSdFactor * options_.noise_sd_floor, options_.noise_sd_floor);
    weights_[k] = 1.0 / (noise_sd_[k] * pooled);
  }
}

std::vector<std::vector<double>> CloudStatsObjective::NoiseDraws(const double* x, int draws) const {
  std::vector<std::vector<double>> v(draws, std::vector<double>(num_residuals_));
  for (int d = 0; d < draws; ++d)
    if (!DrawStatistics(x, d, v[d].data())) throw Error("cloud stats: shape draw " + std::to_string(d) + " failed to render");
  return v;
}

std::vector<double> CloudStatsObjective::NoiseSd(const std::vector<std::vector<double>>& draws) const {
  const int n = num_residuals_;
  const int count = static_cast<int>(draws.size());
  std::vector<double> sd(n);
  for (int k = 0; k < n; ++k) {
    double sum = 0.0, sum2 = 0.0;
    bool all = count >= 2;
    for (const auto& v : draws) {
      all = all && std::isfinite(v[k]);
      sum += v[k];
      sum2 += v[k] * v[k];
    }
    // A statistic some draw leaves empty comes and goes with the shapes (and with the
    // parameters): it makes the cost jump, so it counts for nothing.
    if (!all) {
      sd[k] = kAbsentSdFactor * options_.noise_sd_floor;
      continue;
    }
    const double mean = sum / count;
    sd[k] = std::sqrt(std::max(0.0, (sum2 - count * mean * mean) / (count - 1)));
  }
  return sd;
}

std::vector<double> CloudStatsObjective::EstimateNoiseSd(const double* x, int draws) const {
  return NoiseSd(NoiseDraws(x, draws));
}

double CloudStatsObjective::SetNoiseCovariance(const std::vector<std::vector<double>>& draws, double shrinkage) {
  const int n = num_residuals_, count = static_cast<int>(draws.size());
  if (count < 2) throw Error("cloud stats: a full noise covariance needs at least 2 draws, got " + std::to_string(count));
  for (const auto& v : draws)
    if (static_cast<int>(v.size()) != n)
      throw Error("cloud stats: a draw of " + std::to_string(v.size()) + " statistics for " + std::to_string(n));
  // The statistics every draw fills share one covariance; the others are uncorrelated with
  // a variance that makes them count for nothing (as the diagonal whitening does).
  std::vector<int> present;
  for (int k = 0; k < n; ++k)
    if (std::all_of(draws.begin(), draws.end(), [&](const auto& v) { return std::isfinite(v[k]); })) present.push_back(k);
  const int np = static_cast<int>(present.size());
  Eigen::MatrixXd X(count, np);
  for (int d = 0; d < count; ++d)
    for (int i = 0; i < np; ++i) X(d, i) = draws[d][present[i]];
  double lambda = shrinkage;
  if (lambda < 0.0) {
    lambda = np >= 2 ? DiagonalTargetShrinkage(X) : 1.0;
    // Fewer draws than statistics: S is singular and λ = 0 would leave Σ singular too.
    if (count <= np) lambda = std::max(lambda, 1e-3);
  }
  const double floor2 = options_.noise_sd_floor * options_.noise_sd_floor;
  Eigen::MatrixXd sigma = Eigen::MatrixXd::Zero(n, n);
  if (np > 0) {
    Eigen::MatrixXd S = ShrinkTowardDiagonal(SampleCovariance(X), lambda);
    for (int i = 0; i < np; ++i) S(i, i) = std::max(S(i, i), floor2);
    for (int i = 0; i < np; ++i)
      for (int j = 0; j < np; ++j) sigma(present[i], present[j]) = S(i, j);
  }
  std::vector<double> sd(n, kAbsentSdFactor * options_.noise_sd_floor);
  for (int i = 0; i < np; ++i) sd[present[i]] = std::sqrt(sigma(present[i], present[i]));
  for (int k = 0; k < n; ++k)
    if (sigma(k, k) == 0.0) sigma(k, k) = sd[k] * sd[k];
  // The reference is one draw, the model the mean of M: the difference has (1 + 1/M) Σ.
  sigma *= 1.0 + 1.0 / options_.model_renders;
  SetNoiseSd(sd);  // the per-statistic sd and diagonal weights, for the reading
  whitener_ = std::make_shared<const CovarianceWhitener>(sigma);
  shrinkage_ = lambda;
  return lambda;
}

bool CloudStatsObjective::DrawStatistics(const double* x, int draw, double* values) const {
  const clouds::CloudParams p = ParamsAt(x);
  const int e = static_cast<int>(scene_.shape_draw_maps.size());
  CloudStatsScene sd = scene_;
  if (!scene_.shape_draw_noises.empty()) sd.noise = scene_.shape_draw_noises[draw % scene_.shape_draw_noises.size()];
  for (size_t r = 0; r < refs_.size(); ++r) {
    CloudStatsRender rr;
    try {
      if (e > 0) {
        rr = RenderForCloudStats(refs_[r], sd, p, renderer_, options_, (draw / e) * options_.model_time_step_s,
                                 scene_.shape_draw_maps[draw % e]);
      } else {
        // Past the model's own renders: index M' + draw of the same scheme.
        const int me = std::max<int>(1, static_cast<int>(scene_.weather_ensemble.size()));
        const int m = (options_.model_renders + me - 1) / me * me + draw;
        rr = scene_.weather_ensemble.empty()
                 ? RenderForCloudStats(refs_[r], sd, p, renderer_, options_, m * options_.model_time_step_s)
                 : RenderForCloudStats(refs_[r], sd, p, renderer_, options_, (m / me) * options_.model_time_step_s,
                                       scene_.weather_ensemble[m % me]);
      }
    } catch (const Error&) {
      return false;
    }
    ++renders_;
    Flatten(static_cast<int>(r), ComputeCloudStatistics(rr.composite, rr.opacity, {}, refs_[r].sun_dir, options_), 1,
            values + offsets_[r]);
  }
  return true;
}

std::vector<double> CloudStatsObjective::InitialX() const {
  clouds::CloudParams p = scene_.initial;
  std::vector<double> x;
  for (const Free& f : free_) x.push_back(*f.field(p) / f.scale);
  return x;
}

double CloudStatsObjective::StepX(int i, double x) const {
  const Free& f = free_[i];
  double h = options_.relative_step * (f.max - f.min) / f.scale;
  // Stay inside the bounds: a one-sided excursion past them would render an invalid preset.
  h = std::min(h, 0.25 * (UpperX(i) - LowerX(i)));
  (void)x;
  return h;
}

clouds::CloudParams CloudStatsObjective::ParamsAt(const double* x) const {
  clouds::CloudParams p = scene_.initial;
  for (size_t i = 0; i < free_.size(); ++i)
    *free_[i].field(p) = std::clamp(x[i] * free_[i].scale, free_[i].min, free_[i].max);
  return p;
}

bool CloudStatsObjective::ModelStatistics(const double* x, double* values, std::vector<CloudStatistics>* stats) const {
  const clouds::CloudParams p = ParamsAt(x);
  if (stats) stats->clear();
  for (size_t r = 0; r < refs_.size(); ++r) {
    std::vector<CloudStatsRender> renders(options_.model_renders);
    try {
      const int e = static_cast<int>(scene_.weather_ensemble.size());
      const int nt = static_cast<int>(scene_.noise_textures.size());
      for (int m = 0; m < options_.model_renders; ++m) {
        CloudStatsScene sm = scene_;
        if (nt > 0) sm.noise = scene_.noise_textures[m % nt];
        renders[m] = e > 0 ? RenderForCloudStats(refs_[r], sm, p, renderer_, options_, (m / e) * options_.model_time_step_s,
                                                 scene_.weather_ensemble[m % e])
                           : RenderForCloudStats(refs_[r], sm, p, renderer_, options_, m * options_.model_time_step_s);
      }
    } catch (const Error&) {
      return false;
    }
    renders_ += options_.model_renders;
    std::vector<const ImageRGB*> images;
    std::vector<const std::vector<float>*> opacities;
    for (const auto& rr : renders) {
      images.push_back(&rr.composite);
      opacities.push_back(&rr.opacity);
    }
    const CloudStatistics model = ComputeCloudStatistics(images, opacities, {}, refs_[r].sun_dir, options_);
    Flatten(static_cast<int>(r), model, options_.model_renders, values + offsets_[r]);
    if (stats) stats->push_back(model);
  }
  return true;
}

bool CloudStatsObjective::Evaluate(const double* x, double* residuals, std::vector<CloudStatistics>* stats) const {
  std::vector<double> model(num_residuals_);
  if (!ModelStatistics(x, model.data(), stats)) return false;
  for (int k = 0; k < num_residuals_; ++k) {
    // A bin the model leaves empty (NaN quantiles) costs options_.empty_bin_log_residual log
    // units per quantile (0 by default: then only the share residual sees it).
    const double d = std::isnan(model[k]) ? options_.empty_bin_log_residual : model[k] - ref_values_[k];
    residuals[k] = whitener_ ? d : weights_[k] * d;
    if (!std::isfinite(residuals[k])) return false;
  }
  if (whitener_) whitener_->Apply(residuals, residuals);  // r' = L^-1 r: the full GLS
  return true;
}

}  // namespace skycal::cloudfit
