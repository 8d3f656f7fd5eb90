// Weather maps (clouds/weather_map.h): uniform and procedural maps, the EXR round trip and
// its orientation, and every kind of bad input named in the message.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "test_util.h"
#include "tiling_stats.h"

namespace skycal::clouds {
namespace {

using testing::ScratchDir;

// Runs `f`, expecting a skycal::Error whose message contains every one of `parts`.
template <typename F>
void ExpectErrorNaming(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one naming " << *parts.begin();
  } catch (const Error& e) {
    for (const std::string& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << "\n  missing: " << p;
  }
}

double ChannelMean(const WeatherMap& m, int c) {
  double s = 0.0;
  for (size_t i = c; i < m.rgb.size(); i += 3) s += m.rgb[i];
  return s / (m.rgb.size() / 3);
}

TEST(WeatherMap, UniformMapHoldsItsValues) {
  const WeatherMap m = UniformWeatherMap(0.6, 0.1, 0.5, 20000.0);
  EXPECT_EQ(m.width, 4);
  EXPECT_EQ(m.height, 4);
  EXPECT_EQ(m.extent_m, 20000.0);
  ASSERT_EQ(m.rgb.size(), 48u);
  for (size_t i = 0; i < m.rgb.size(); i += 3) {
    EXPECT_EQ(m.rgb[i], 0.6f);
    EXPECT_EQ(m.rgb[i + 1], 0.1f);
    EXPECT_EQ(m.rgb[i + 2], 0.5f);
  }
  ExpectErrorNaming([] { UniformWeatherMap(1.5, 0, 0, 1000); }, {"uniform weather map", "R (coverage)", "1.5"});
  ExpectErrorNaming([] { UniformWeatherMap(0.5, -0.1, 0, 1000); }, {"G (precipitation)", "-0.1"});
  ExpectErrorNaming([] { UniformWeatherMap(0.5, 0, NAN, 1000); }, {"B (cloud type)", "NaN"});
  ExpectErrorNaming([] { UniformWeatherMap(0.5, 0, 0, 0); }, {"extent 0"});
}

TEST(WeatherMap, NoiseMapHitsTheRequestedMeansAndStaysInRange) {
  for (double mean : {0.1, 0.5, 0.8}) {
    WeatherNoiseOptions o;
    o.mean_coverage = mean;
    o.mean_precipitation = 0.3;
    o.mean_type = 1.0 - mean;
    const WeatherMap m = NoiseWeatherMap(5, 128, 40000.0, o);
    ASSERT_EQ(m.width, 128);
    // 1e-3: the offset is bisected to 1e-7 and float storage rounds by ~1e-8; the 1e-3
    // allows for the clamp's flat ends making the mean a step function at extreme means.
    EXPECT_NEAR(ChannelMean(m, 0), mean, 1e-3);
    EXPECT_NEAR(ChannelMean(m, 1), 0.3, 1e-3);
    EXPECT_NEAR(ChannelMean(m, 2), 1.0 - mean, 1e-3);
    float lo = 1, hi = 0;
    for (size_t i = 0; i < m.rgb.size(); i += 3) lo = std::min(lo, m.rgb[i]), hi = std::max(hi, m.rgb[i]);
    // Contrast 1.5 (the default) spreads coverage: a map with clouds and gaps, not a
    // uniform grey. Measured spans: 0.37 at mean 0.1 (mostly clear sky, the clamp at 0
    // takes the lower part), about 1 at 0.5 and 0.8.
    EXPECT_GT(hi - lo, 0.3) << "mean " << mean;
  }
}

TEST(WeatherMap, NoiseMapIsDeterministicAndTiles) {
  const WeatherMap a = NoiseWeatherMap(9, 64, 1000.0, {}), b = NoiseWeatherMap(9, 64, 1000.0, {});
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_NE(NoiseWeatherMap(10, 64, 1000.0, {}).rgb, a.rgb);
  for (int c = 0; c < 3; ++c)
    for (int axis = 0; axis < 2; ++axis) {
      auto texel = [&](int i, int j, int) {
        const int x = axis == 0 ? i : j, y = axis == 0 ? j : i;
        return a.rgb[(static_cast<size_t>(y) * 64 + x) * 3 + c];
      };
      const auto v = testing::JudgeSeam(testing::PlaneStepMeans(texel, 64, 64, 1));
      EXPECT_TRUE(v.tiles()) << "channel " << c << " axis " << axis << " seam " << v.seam << " interior "
                             << v.interior_mean << " +- " << v.interior_sd << ", z " << v.z;
    }
}

TEST(WeatherMap, FineCellsOnALargeMapUseAPlanarWorleyTable) {
  // 512 cells across a 1024-texel map: a cubic Worley table would be 512^3 points, 1.6 GB;
  // the planar one is 3 MB. The map is valid and still has the requested mean.
  WeatherNoiseOptions o;
  o.coverage_cells = 512;
  const WeatherMap m = NoiseWeatherMap(2, 1024, 50000.0, o);
  EXPECT_EQ(m.width, 1024);
  EXPECT_NEAR(ChannelMean(m, 0), o.mean_coverage, 1e-3);
}

TEST(WeatherMap, NoiseOptionsNameTheBadField) {
  auto invalid = [](WeatherNoiseOptions o, const std::string& field) {
    std::string why;
    EXPECT_FALSE(o.IsValid(&why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
    ExpectErrorNaming([&] { NoiseWeatherMap(1, 64, 1000.0, o); }, {field});
  };
  std::string why;
  EXPECT_TRUE(WeatherNoiseOptions{}.IsValid(&why)) << why;
  WeatherNoiseOptions o;
  o.mean_coverage = 1.2;
  invalid(o, "mean_coverage");
  o = {};
  o.coverage_contrast = -1;
  invalid(o, "coverage_contrast");
  o = {};
  o.coverage_cells = 0;
  invalid(o, "coverage_cells");
  o = {};
  o.mean_precipitation = NAN;
  invalid(o, "mean_precipitation");
  o = {};
  o.type_contrast = 100;
  invalid(o, "type_contrast");
  o = {};
  o.octaves = 9;
  invalid(o, "octaves");
  o = {};
  o.coverage_cells = 64;  // valid alone, too fine for 64 texels
  ExpectErrorNaming([&] { NoiseWeatherMap(1, 64, 1000.0, o); }, {"coverage_cells", "64-texel"});
  ExpectErrorNaming([] { NoiseWeatherMap(1, 100, 1000.0, {}); }, {"100 x 100", "power of two"});
}

// Resampling (calibrate's statistics map to the inverted map's finer grid): the same size
// is the identity; a field linear across the map comes back on the finer grid's texel
// centres exactly (bilinear reproduces a linear field) away from the wrap seam, where the
// tiling blends the two edges; a coarser grid averages. Control: nearest-texel lookup is
// off by up to half a texel's step.
TEST(WeatherMap, ResamplingKeepsTheFieldTheMarchSees) {
  WeatherMap m = UniformWeatherMap(0.0, 0.0, 0.5, 60000.0);
  m.width = m.height = 16;
  m.rgb.assign(16 * 16 * 3, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      m.rgb[(y * 16 + x) * 3] = static_cast<float>(0.05 * x);  // linear in x: 0 .. 0.75
      m.rgb[(y * 16 + x) * 3 + 1] = static_cast<float>(0.04 * y);
      m.rgb[(y * 16 + x) * 3 + 2] = 0.5f;
    }
  const WeatherMap same = ResampleWeatherMap(m, 16);
  EXPECT_EQ(same.rgb, m.rgb);
  const WeatherMap fine = ResampleWeatherMap(m, 32);
  EXPECT_EQ(fine.width, 32);
  EXPECT_EQ(fine.extent_m, m.extent_m);
  double worst = 0.0, nearest_worst = 0.0;
  for (int y = 2; y < 30; ++y)
    for (int x = 2; x < 30; ++x) {  // away from the seam
      const double u = (x + 0.5) / 2.0 - 0.5;  // the old grid's coordinate, texel centre at i
      const double v = (y + 0.5) / 2.0 - 0.5;
      const float* t = &fine.rgb[(y * 32 + x) * 3];
      worst = std::max({worst, std::abs(t[0] - 0.05 * u), std::abs(t[1] - 0.04 * v), std::abs(t[2] - 0.5)});
      nearest_worst = std::max(nearest_worst, std::abs(0.05 * (x / 2) - 0.05 * u));
    }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(nearest_worst, 0.01);
  const WeatherMap coarse = ResampleWeatherMap(m, 8);
  EXPECT_NEAR(coarse.rgb[(3 * 8 + 3) * 3], 0.05 * 6.5, 1e-6);  // midway between old texels 6 and 7
  EXPECT_THROW(ResampleWeatherMap(m, 24), Error);               // not a power of two
}

TEST(WeatherMap, ExrRoundTripKeepsEveryTexelAndPutsRowZeroAtTheTop) {
  ScratchDir dir("weather-rt");
  const WeatherMap m = NoiseWeatherMap(3, 32, 30000.0, {});
  SaveWeatherMap(m, dir / "w.exr");
  const WeatherMap back = LoadWeatherMap(dir / "w.exr", 30000.0);
  EXPECT_EQ(back.width, 32);
  EXPECT_EQ(back.height, 32);
  EXPECT_EQ(back.extent_m, 30000.0);
  EXPECT_EQ(back.rgb, m.rgb);  // float EXR: bit exact
  // Map row 0 (-z) is the EXR's first row (the top of the image).
  const ExrRGB raw = ReadExrRGB(dir / "w.exr");
  for (int x = 0; x < 32; ++x) EXPECT_EQ(raw.image.at(x, 0, 0), m.rgb[x * 3]);
}

TEST(WeatherMap, SavingABadMapThrowsAndWritesNothing) {
  ScratchDir dir("weather-bad-save");
  WeatherMap m = UniformWeatherMap(0.5, 0, 0, 1000.0);
  m.rgb[7] = 2.0f;
  ExpectErrorNaming([&] { SaveWeatherMap(m, dir / "w.exr"); }, {"w.exr", "x 2, y 0", "G (precipitation)"});
  EXPECT_EQ(dir.CountEntries(), 0);
}

// ---- Bad files. ----

void WriteMap(const std::string& path, int w, int h, float value = 0.5f) {
  ImageRGB img(w, h);
  std::fill(img.pixels.begin(), img.pixels.end(), value);
  WriteExrRGB(path, img, {});
}

TEST(WeatherMapFile, MissingFileIsNamed) {
  ScratchDir dir("weather-missing");
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "nope.exr", 1000.0); }, {"nope.exr", "no such file", "weather map"});
}

TEST(WeatherMapFile, WrongChannelsAreNamed) {
  ScratchDir dir("weather-channels");
  // R and G only (a two-channel file), written with OpenEXR itself: skycal's writer always
  // writes R, G, B.
  {
    Imf::Header header(8, 8);
    header.channels().insert("R", Imf::Channel(Imf::FLOAT));
    header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    std::vector<float> plane(64, 0.5f);
    Imf::FrameBuffer fb;
    for (const char* c : {"R", "G"})
      fb.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(plane.data()), sizeof(float), 8 * sizeof(float)));
    Imf::OutputFile out((dir / "rg.exr").c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(8);
  }
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "rg.exr", 1000.0); }, {"rg.exr", "'B' missing", "RGB"});
  // R, G, B plus a depth channel: refused; R, G, B, A: the alpha is ignored.
  ImageRGB img(8, 8);
  WriteExrRGBWithPlanes(dir / "rgbz.exr", img, {{"Z", std::vector<float>(64, 1.0f)}}, {});
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "rgbz.exr", 1000.0); }, {"rgbz.exr", "B,G,R,Z", "expected R, G, B"});
  WriteExrRGBWithPlanes(dir / "rgba.exr", img, {{"A", std::vector<float>(64, 1.0f)}}, {});
  EXPECT_EQ(LoadWeatherMap(dir / "rgba.exr", 1000.0).width, 8);
}

TEST(WeatherMapFile, WrongSizesAreNamed) {
  ScratchDir dir("weather-size");
  WriteMap(dir / "wide.exr", 8, 4);
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "wide.exr", 1000.0); }, {"wide.exr", "8 x 4", "square power of two"});
  WriteMap(dir / "six.exr", 6, 6);
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "six.exr", 1000.0); }, {"six.exr", "6 x 6"});
  WriteMap(dir / "tiny.exr", 2, 2);
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "tiny.exr", 1000.0); }, {"tiny.exr", "2 x 2", "from 4 to 4096"});
  // Too large: refused by the header, before the pixels. The file holds a header claiming
  // 8192 x 8192 and no pixels (an 800 MB float map, had it been read).
  {
    Imf::Header header(8192, 8192);
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile out((dir / "huge.exr").c_str(), header);
  }
  ASSERT_LT(std::filesystem::file_size(dir / "huge.exr"), 200000u);
  ExpectErrorNaming([&] { LoadWeatherMap(dir / "huge.exr", 1000.0); }, {"huge.exr", "8192 x 8192", "from 4 to 4096"});
  // And on a map in memory: size comes first.
  WeatherMap big;
  big.width = big.height = 8192;
  big.extent_m = 1000.0;
  ExpectErrorNaming([&] { ValidateWeatherMap(big, "big.exr"); }, {"big.exr", "8192 x 8192"});
}

TEST(WeatherMapFile, BadTexelsAreNamedByPixelAndChannel) {
  ScratchDir dir("weather-texels");
  struct Case {
    float value;
    int x, y, c;
    const char* says;
  };
  const Case cases[] = {{NAN, 2, 3, 1, "NaN"},
                        {std::numeric_limits<float>::infinity(), 0, 7, 0, "infinite"},
                        {-0.25f, 5, 1, 2, "-0.25"},
                        {1.5f, 7, 7, 0, "1.5"}};
  const char* channel[3] = {"R (coverage)", "G (precipitation)", "B (cloud type)"};
  for (const Case& k : cases) {
    ImageRGB img(8, 8);
    std::fill(img.pixels.begin(), img.pixels.end(), 0.5f);
    img.at(k.x, k.y, k.c) = k.value;
    WriteExrRGB(dir / "bad.exr", img, {});
    const std::string pixel = "x " + std::to_string(k.x) + ", y " + std::to_string(k.y);
    ExpectErrorNaming([&] { LoadWeatherMap(dir / "bad.exr", 1000.0); }, {"bad.exr", pixel, channel[k.c], k.says});
  }
  // The bounds themselves are valid.
  WriteMap(dir / "zero.exr", 8, 8, 0.0f);
  WriteMap(dir / "one.exr", 8, 8, 1.0f);
  EXPECT_NO_THROW(LoadWeatherMap(dir / "zero.exr", 1000.0));
  EXPECT_NO_THROW(LoadWeatherMap(dir / "one.exr", 1000.0));
}

TEST(WeatherMapFile, BadExtentsAreNamed) {
  ScratchDir dir("weather-extent");
  WriteMap(dir / "w.exr", 8, 8);
  for (double extent : {0.0, -5.0, 2.0e6, static_cast<double>(NAN), static_cast<double>(INFINITY)})
    ExpectErrorNaming([&] { LoadWeatherMap(dir / "w.exr", extent); }, {"w.exr", "extent"});
  EXPECT_NO_THROW(LoadWeatherMap(dir / "w.exr", 1.0e6));  // 1000 km exactly: the bound is inclusive
}

}  // namespace
}  // namespace skycal::clouds
