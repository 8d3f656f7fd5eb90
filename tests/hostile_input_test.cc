// Hostile input through the binary: each class of bad input that used to pass silently or
// fail late is refused up front with the file, field or option named (or handled, where it
// can be), exit 1, nothing written.
#include <gtest/gtest.h>

#include <ImfHeader.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfDeepFrameBuffer.h>
#include <ImfDeepScanLineOutputFile.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/exr_io.h"
#include "test_util.h"

namespace skycal {
namespace {
namespace fs = std::filesystem;

using testing::ProcessResult;
using testing::ScratchDir;

ProcessResult Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

void ExpectRefused(const std::string& args, const std::vector<std::string>& needles, const ScratchDir& dir) {
  const int before = dir.CountEntries();
  const ProcessResult r = Skycal(args);
  EXPECT_EQ(r.rc, 1) << args << "\n" << r.err;
  for (const auto& n : needles) EXPECT_NE(r.err.find(n), std::string::npos) << "expected '" << n << "' in: " << r.err;
  EXPECT_EQ(dir.CountEntries(), before) << "output left behind by: " << args;
}

std::string Render(const ScratchDir& dir, const std::string& name, const std::string& size = "128x64") {
  const ProcessResult r = Skycal("render --sun-elevation 25 --sun-azimuth 40 --backend cpu --size " + size + " --out " +
                                 (dir / name));
  EXPECT_EQ(r.rc, 0) << r.err;
  return dir / name;
}

TEST(HostileInput, AbsurdPhysicalParametersAreRefused) {
  ScratchDir dir("hostile-physics");
  ExpectRefused("bake --mie-scattering 1e300 --out " + (dir / "p.json"), {"mie_scattering_per_m", "1e+300", "optical depth"},
                dir);
  ExpectRefused("bake --rayleigh-scale-height 1e-9 --out " + (dir / "p.json"), {"rayleigh_scale_height_m"}, dir);
  ExpectRefused("sun --time 2026-06-21T12:00:00Z --lat 48 --lon 11 --elevation-m 1e12", {"--elevation-m", "1e+12"}, dir);
  ExpectRefused("sun --time 2026-06-21T12:00:00Z --lat 48 --lon 11 --pressure 4000", {"--pressure"}, dir);
  // A render that fit and import would reject is not written in the first place.
  ExpectRefused("render --sun-elevation 10 --sun-azimuth 0 --size 100x100 --out " + (dir / "sq.exr"), {"2:1"}, dir);
}

// The issue's example through the binary: a misspelt preset key used to be ignored (its
// default used, exit 0); now the run fails naming the key and the nearest valid one.
TEST(HostileInput, AMisspeltPresetKeyFailsTheRun) {
  ScratchDir dir("hostile-preset");
  ASSERT_EQ(Skycal("bake --out " + (dir / "p.json")).rc, 0);
  std::string text = testing::Slurp(dir / "p.json");
  const size_t at = text.find("\"haziness_g\"");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 12, "\"haziness\"");
  std::ofstream(dir / "typo.json") << text;
  ExpectRefused("render --sun-elevation 10 --sun-azimuth 0 --preset " + (dir / "typo.json") + " --out " + (dir / "o.exr"),
                {"typo.json", "field 'parameters.haziness': unknown key (did you mean 'haziness_g'?"}, dir);
  std::ofstream(dir / "rig.json") << R"({"cameras": [{"image": "sky.exr"}]})";
  ExpectRefused("capture --rig " + (dir / "rig.json") + " --out " + (dir / "c.exr"),
                {"rig.json", "field 'format_version' is missing"}, dir);
}

// Replaces the dataWindow box of a small scanline EXR with one of 65536 x 32768: the
// reader must refuse from the header, before allocating 25 GB.
TEST(HostileInput, AnImageSizeBeyondTheLimitIsRefusedFromTheHeader) {
  ScratchDir dir("hostile-size");
  const std::string small = Render(dir, "small.exr");
  std::string bytes = testing::Slurp(small);
  const std::string tag = std::string("dataWindow") + '\0' + "box2i" + '\0';
  const size_t at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos);
  const int32_t box[4] = {0, 0, 65535, 32767};  // min.x, min.y, max.x, max.y (little-endian on x86)
  std::memcpy(&bytes[at + tag.size() + 4], box, sizeof box);
  std::ofstream(dir / "huge.exr", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ExpectRefused("fit --quiet --reference " + (dir / "huge.exr") + " --out " + (dir / "out"),
                {"huge.exr", "65536 x 32768", "limit"}, dir);
  ExpectRefused("probe-extract --image " + (dir / "huge.exr") + " --out " + (dir / "s.json"), {"huge.exr", "limit"}, dir);
}

TEST(HostileInput, AMultiPartExrIsRefusedListingItsParts) {
  ScratchDir dir("hostile-multipart");
  std::vector<Imf::Header> headers;
  for (const char* name : {"beauty", "sky"}) {
    Imf::Header h(8, 4);
    h.setName(name);
    h.setType(Imf::SCANLINEIMAGE);
    for (const char* c : {"R", "G", "B"}) h.channels().insert(c, Imf::Channel(Imf::FLOAT));
    headers.push_back(h);
  }
  {
    Imf::MultiPartOutputFile file((dir / "parts.exr").c_str(), headers.data(), static_cast<int>(headers.size()));
    std::vector<float> px(8 * 4 * 3, 1.0f);
    for (int p = 0; p < 2; ++p) {
      Imf::OutputPart part(file, p);
      Imf::FrameBuffer fb;
      for (int c = 0; c < 3; ++c) {
        fb.insert(std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(px.data() + c), 12, 12 * 8));
      }
      part.setFrameBuffer(fb);
      part.writePixels(4);
    }
  }
  ExpectRefused("probe-extract --image " + (dir / "parts.exr") + " --out " + (dir / "s.json"),
                {"parts.exr", "multi-part", "'beauty'", "'sky'"}, dir);
}

TEST(HostileInput, ADeepExrIsRefused) {
  ScratchDir dir("hostile-deep");
  const int w = 8, h = 4;
  Imf::Header header(w, h);
  header.setType(Imf::DEEPSCANLINE);
  header.compression() = Imf::ZIPS_COMPRESSION;
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  std::vector<unsigned int> counts(w * h, 1);
  std::vector<float> values(w * h, 1.0f);
  std::vector<float*> pointers(w * h);
  for (int i = 0; i < w * h; ++i) pointers[i] = &values[i];
  {
    Imf::DeepScanLineOutputFile file((dir / "deep.exr").c_str(), header);
    Imf::DeepFrameBuffer fb;
    fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(unsigned int),
                                         sizeof(unsigned int) * w));
    for (const char* c : {"R", "G", "B"}) {
      fb.insert(c, Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(pointers.data()), sizeof(float*), sizeof(float*) * w,
                                  sizeof(float)));
    }
    file.setFrameBuffer(fb);
    file.writePixels(h);
  }
  ExpectRefused("probe-extract --image " + (dir / "deep.exr") + " --out " + (dir / "s.json"), {"deep.exr", "deep EXR"}, dir);
}

// Values the camera's units make extreme are still a sky: the exposure is free, so the fit
// works in a rescaled copy and reports the exposure in the file's own units.
TEST(HostileInput, ExtremeButValidRadianceScalesAreHandled) {
  ScratchDir dir("hostile-scale");
  const std::string ref = Render(dir, "ref.exr");
  for (const double scale : {1e-36, 1e30}) {
    capture::LatLongFrame f = capture::ReadLatLongFrame(ref);
    for (float& v : f.radiance.pixels) v = static_cast<float>(v * scale);
    const std::string path = dir / "scaled.exr";
    capture::WriteLatLongFrame(path, f);
    const ProcessResult r = Skycal("fit --quiet --backend cpu --reference " + path + " --out " + (dir / "out") + " --json");
    ASSERT_EQ(r.rc, 0) << scale << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_LT(j["references"][0]["rel_rmse"].get<double>(), 0.01) << scale;
    const double exposure = j["references"][0]["exposure"].get<double>();
    EXPECT_NEAR(std::log10(exposure), std::log10(scale), 0.05) << scale;
    fs::remove_all(dir.path() / "out");
  }
  // Beyond float's normal range there is nothing to fit: refused naming the file.
  capture::LatLongFrame f = capture::ReadLatLongFrame(ref);
  for (float& v : f.radiance.pixels) v = 1e-40f;
  capture::WriteLatLongFrame(dir / "denormal.exr", f);
  ExpectRefused("fit --quiet --reference " + (dir / "denormal.exr") + " --out " + (dir / "out"), {"denormal.exr"}, dir);
}

// Metadata errors name the attribute and the file, not an option the user never gave.
TEST(HostileInput, BadAttributesAreNamed) {
  ScratchDir dir("hostile-attributes");
  const std::string ref = Render(dir, "ref.exr");
  capture::LatLongFrame f = capture::ReadLatLongFrame(ref);
  f.extra.floats["skycalTimeOfDay"] = 31.0f;
  capture::WriteLatLongFrame(dir / "late.exr", f);
  ExpectRefused("fit --quiet --reference " + (dir / "late.exr") + " --out " + (dir / "out"),
                {"late.exr", "attribute 'skycalTimeOfDay' = 31"}, dir);
  f = capture::ReadLatLongFrame(ref);
  f.sun_direction.reset();
  f.extra.strings["sunDirection"] = "0.5,0.5,0.7";
  capture::WriteLatLongFrame(dir / "text.exr", f);
  ExpectRefused("fit --quiet --reference " + (dir / "text.exr") + " --out " + (dir / "out"),
                {"text.exr", "attribute 'sunDirection' is a string", "expected a v3f"}, dir);
}

TEST(HostileInput, ANonUtf8FileNameIsHandled) {
  ScratchDir dir("hostile-utf8");
  const std::string ref = Render(dir, "ref.exr");
  const std::string odd = dir / "sky\xff\xfe.exr";
  fs::copy(ref, odd);
  const ProcessResult r = Skycal("fit --quiet --backend cpu --reference '" + odd + "' --out " + (dir / "out") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);  // valid JSON: the bytes are replaced, not fatal
  EXPECT_LT(j["references"][0]["rel_rmse"].get<double>(), 0.01);
  EXPECT_TRUE(fs::exists(dir.path() / "out/preset.json"));
}

}  // namespace
}  // namespace skycal
