// EXR and preset files: round trips and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"
#include "skycal/core/sha256.h"
#include "skycal/render/preset.h"
#include "test_presets.h"
#include "test_util.h"

namespace skycal {
namespace {

using testing::ScratchDir;

ImageRGB Gradient(int w, int h) {
  ImageRGB img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(std::exp(0.01 * (x + 3 * y) + c));
  return img;
}

TEST(ExrIo, LatLongFrameRoundTripKeepsPixelsAndAttributes) {
  ScratchDir dir("exr");
  capture::LatLongFrame f;
  f.radiance = Gradient(64, 32);
  f.sun_direction = std::array<double, 3>{0.6, 0.8, 0.0};
  f.extra.strings["skycalPreset"] = "x.json";
  f.extra.floats["exposureScale"] = 2.5f;
  capture::WriteLatLongFrame(dir / "f.exr", f);
  const capture::LatLongFrame g = capture::ReadLatLongFrame(dir / "f.exr");
  ASSERT_EQ(g.radiance.width, 64);
  EXPECT_EQ(g.radiance.pixels, f.radiance.pixels);  // float: bit exact
  ASSERT_TRUE(g.sun_direction.has_value());
  EXPECT_NEAR((*g.sun_direction)[0], 0.6, 1e-7);
  EXPECT_NEAR((*g.sun_direction)[1], 0.8, 1e-7);
  EXPECT_EQ(g.extra.strings.at("skycalPreset"), "x.json");
  EXPECT_EQ(g.extra.floats.at("exposureScale"), 2.5f);
  EXPECT_EQ(g.extra.strings.count("skycalWarning"), 0u);  // envmap attribute was written
  const ExrRGB raw = ReadExrRGB(dir / "f.exr");
  EXPECT_TRUE(raw.attributes.envmap_latlong);
}

TEST(ExrIo, HalfRoundTripWithinHalfPrecisionAndCountsOverflow) {
  ScratchDir dir("half");
  ImageRGB img = Gradient(32, 16);
  img.at(3, 3, 0) = 1e6f;  // beyond half range
  const ExrWriteReport rep = WriteExrRGB(dir / "h.exr", img, {}, ExrPixelType::kHalf);
  EXPECT_EQ(rep.half_overflow_count, 1);
  const ExrRGB back = ReadExrRGB(dir / "h.exr");
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    if (img.pixels[i] > 65504.0f) continue;
    EXPECT_NEAR(back.image.pixels[i], img.pixels[i], img.pixels[i] * 4.9e-4);  // half: 2^-11 relative
  }
}

TEST(ExrIo, BadFilesGiveClearErrors) {
  ScratchDir dir("badexr");
  WriteExrRGB(dir / "good.exr", Gradient(64, 32), {});
  // Truncated file.
  {
    std::ifstream in(dir / "good.exr", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir / "trunc.exr", std::ios::binary).write(bytes.data(), bytes.size() / 2);
  }
  try {
    ReadExrRGB(dir / "trunc.exr");
    FAIL() << "truncated file accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("trunc.exr"), std::string::npos) << e.what();
  }
  testing::WriteText(dir / "text.exr", "not an exr");
  EXPECT_THROW(ReadExrRGB(dir / "text.exr"), Error);
  try {
    ReadExrRGB(dir / "missing.exr");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos);
  }
  // Not 2:1 as a lat-long frame.
  WriteExrRGB(dir / "square.exr", Gradient(32, 32), {});
  EXPECT_THROW(capture::ReadLatLongFrame(dir / "square.exr"), Error);
}

// A valid 8x4 file whose header is patched to claim a width x height data window, with a
// zeroed line-offset table long enough for OpenEXR to open it: a few KB that claim
// gigabytes (fuzz/exr_frame_fuzzer found the readers allocating what such a header says).
std::string FileClaimingSize(const ScratchDir& dir, int width, int height) {
  WriteExrRGB(dir / "small.exr", Gradient(8, 4), {});
  std::ifstream in(dir / "small.exr", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string key("dataWindow\0box2i\0", 17);
  const size_t at = bytes.find(key);
  EXPECT_NE(at, std::string::npos);
  const int32_t box[4] = {0, 0, width - 1, height - 1};
  bytes.replace(at + key.size() + 4, sizeof(box), reinterpret_cast<const char*>(box), sizeof(box));
  bytes.append(8 * (static_cast<size_t>(height) / 16 + 1), '\0');  // ZIP: 16 lines per offset
  const std::string path = dir / (std::to_string(width) + "x" + std::to_string(height) + ".exr");
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

TEST(ExrIo, HeaderClaimingAHugeImageIsRefusedBeforeAllocating) {
  ScratchDir dir("hugeexr");
  // Sides within OpenEXR's 32768 but taller than skycal's 16384 (20000 x 20000 = 400
  // Mpixels, 4.8 GB of RGB floats): our check (image.h).
  const std::string many = FileClaimingSize(dir, 20000, 20000);
  for (int reader = 0; reader < 2; ++reader) {
    try {
      if (reader == 0) {
        ReadExrRGB(many);
      } else {
        int w = 0, h = 0;
        ReadExrChannel(many, "R", &w, &h);
      }
      FAIL() << "a 20000x20000 header was read";
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(many), std::string::npos) << m;
      EXPECT_NE(m.find("20000 x 20000 pixels is larger than skycal's limit"), std::string::npos) << m;
    }
  }
  // A side beyond 4 x 32768: OpenEXR's own header check (set by the readers) refuses it before
  // it allocates its line-offset table.
  const std::string wide = FileClaimingSize(dir, 1 << 20, 64);
  try {
    ReadExrRGB(wide);
    FAIL() << "a 1048576-wide header was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(wide), std::string::npos) << e.what();
  }
  // The widest accepted image still reads (the limit is not off by one): 32768 x 2.
  ImageRGB strip(kMaxExrSide, 2);
  WriteExrRGB(dir / "strip.exr", strip, {});
  EXPECT_EQ(ReadExrRGB(dir / "strip.exr").image.width, kMaxExrSide);
}

TEST(ExrIo, AttributeClaimingMoreBytesThanTheFileIsRefused) {
  // An attribute of a type OpenEXR does not know, claiming 1.6 GB: OpenEXR would allocate
  // that before finding the file too short (fuzz/exr_frame_fuzzer).
  ScratchDir dir("attrexr");
  WriteExrRGB(dir / "small.exr", Gradient(8, 4), {});
  std::ifstream in(dir / "small.exr", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const char claim[] = {'j', 'u', 'n', 'k', 0, 'b', 'l', 'o', 'b', 0, 0x00, 0x00, 0x68, 0x61};  // 0x61680000 bytes
  bytes.insert(8, claim, sizeof(claim));
  std::ofstream(dir / "claim.exr", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  try {
    ReadExrRGB(dir / "claim.exr");
    FAIL() << "a header attribute longer than the file was read";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("claim.exr"), std::string::npos) << m;
    EXPECT_NE(m.find("attribute 'junk' claims 1634205696 bytes"), std::string::npos) << m;
  }
  EXPECT_EQ(ReadExrRGB(dir / "small.exr").image.width, 8);  // an intact header passes
}

TEST(ExrIo, AFixedSizeAttributeWithAnotherDeclaredSizeIsRefused) {
  // OpenEXR reads a box2i as 16 bytes whatever size the header declares, and parses the
  // rest of the header shifted (fuzz/exr_frame_fuzzer: a 465-byte file, 2 GB allocated).
  ScratchDir dir("fixedexr");
  WriteExrRGB(dir / "small.exr", Gradient(8, 4), {});
  std::ifstream in(dir / "small.exr", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string tag = std::string("dataWindow") + '\0' + "box2i" + '\0';
  const size_t at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos);
  bytes[at + tag.size()] = 3;  // the declared size (little-endian int32): 16 -> 3
  std::ofstream(dir / "shifted.exr", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  try {
    ReadExrRGB(dir / "shifted.exr");
    FAIL() << "a box2i declaring 3 bytes was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("attribute 'dataWindow' (box2i) declares 3 bytes, its type has 16"),
              std::string::npos)
        << e.what();
  }
}

TEST(ExrIo, UnwritableOutputLeavesNothing) {
  ScratchDir dir("unwritable");
  EXPECT_THROW(WriteExrRGB(dir / "no/such/dir/x.exr", Gradient(8, 4), {}), Error);
  std::filesystem::create_directory(dir / "ro");
  std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  if (::geteuid() != 0) {  // root ignores permission bits
    EXPECT_THROW(WriteExrRGB(dir / "ro/x.exr", Gradient(8, 4), {}), Error);
  }
  EXPECT_EQ(dir.CountEntries(), 1);  // only "ro"
}

TEST(PresetIo, RoundTripIsExact) {
  ScratchDir dir("preset");
  render::Preset p = testing::RandomPreset(9, render::ModelVariant::kFfxvIso);
  p.name = "roundtrip";
  p.haziness_g = 0.8312345;
  p.sun_tint_rgb = {1.0, 0.9, 0.8};
  p.overcast_weight = 0.25;
  render::SavePreset(p, dir / "p.json");
  const render::Preset q = render::LoadPreset(dir / "p.json");
  EXPECT_EQ(q.name, "roundtrip");
  EXPECT_EQ(q.variant, render::ModelVariant::kFfxvIso);
  EXPECT_EQ(q.haziness_g, p.haziness_g);
  EXPECT_EQ(q.sun_tint_rgb, p.sun_tint_rgb);
  EXPECT_EQ(q.overcast_weight, p.overcast_weight);
  EXPECT_EQ(q.luts.rayleigh, p.luts.rayleigh);
  EXPECT_EQ(q.luts.mie, p.luts.mie);
  EXPECT_EQ(q.luts.isotropic, p.luts.isotropic);
  EXPECT_EQ(q.luts.sun_transmittance, p.luts.sun_transmittance);
  const auto j = ReadJsonFile(dir / "p.json");
  EXPECT_EQ(j["parameters"]["haziness_g"]["unit"], "1");
  EXPECT_EQ(j["parameters"]["sun_illuminance"]["unit"], "lux");
  EXPECT_EQ(j["parameters"]["overcast_zenith_luminance"]["unit"], "cd/m^2");
}

// Writes a valid preset, applies `edit` to its JSON, and expects LoadPreset to fail with a
// message containing `expect`.
void ExpectPresetError(const std::function<void(nlohmann::json&)>& edit, const std::string& expect) {
  ScratchDir dir("badpreset");
  render::SavePreset(testing::RandomPreset(1, render::ModelVariant::kFfxv), dir / "p.json");
  nlohmann::json j = ReadJsonFile(dir / "p.json");
  edit(j);
  testing::WriteText(dir / "p.json", j.dump());
  try {
    render::LoadPreset(dir / "p.json");
    FAIL() << "accepted; expected an error containing '" << expect << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("p.json"), std::string::npos) << e.what();
  }
}

TEST(PresetIo, BadPresetsNameTheField) {
  ExpectPresetError([](auto& j) { j["parameters"]["haziness_g"]["value"] = 1.5; }, "haziness_g");
  ExpectPresetError([](auto& j) { j["parameters"]["sun_illuminance"]["value"] = -1; }, "sun_illuminance");
  ExpectPresetError([](auto& j) { j["parameters"]["overcast_weight"]["value"] = "half"; }, "overcast_weight");
  ExpectPresetError([](auto& j) { j["parameters"]["sun_tint_rgb"]["value"] = {1, 2}; }, "sun_tint_rgb");
  ExpectPresetError([](auto& j) { j["model"] = "bruneton"; }, "unknown model variant 'bruneton'");
  ExpectPresetError([](auto& j) { j["format"] = "something-else"; }, "format");
  ExpectPresetError([](auto& j) { j["luts"]["mie"] = "missing.exr"; }, "missing.exr");
  ExpectPresetError([](auto& j) { j["luts"]["grid"]["n_theta"] = 12; }, "expected 32 x 12");
  ExpectPresetError([](auto& j) { j.erase("luts"); }, "luts");
  // Strict: a misspelt or unknown key is an error naming the nearest valid name, a missing
  // parameter is an error (not its default), a later format_version is refused.
  ExpectPresetError(
      [](auto& j) {
        j["parameters"]["haziness"] = j["parameters"]["haziness_g"];
        j["parameters"].erase("haziness_g");
      },
      "field 'parameters.haziness': unknown key (did you mean 'haziness_g'?");
  ExpectPresetError([](auto& j) { j["parameters"].erase("ground_albedo"); }, "field 'parameters.ground_albedo' is missing");
  ExpectPresetError([](auto& j) { j["sun_angle"] = 3; }, "field 'sun_angle': unknown key");
  ExpectPresetError([](auto& j) { j["parameters"]["haziness_g"]["vaule"] = 0.5; }, "did you mean 'value'?");
  ExpectPresetError([](auto& j) { j["luts"]["raleigh"] = "x.exr"; }, "did you mean 'rayleigh'?");
  ExpectPresetError([](auto& j) { j["format_version"] = 2; }, "newer skycal");
  ExpectPresetError([](auto& j) { j.erase("format_version"); }, "field 'format_version' is missing");
  ExpectPresetError([](auto& j) { j["luts"]["grid"]["n_theta"] = 1e300; }, "expected an integer in [2, ");
  ExpectPresetError([](auto& j) { j["parameters"]["sun_illuminance"]["value"] = 1e300; }, "1e+300 is out of range");
  // Grid sizes outside int's range: rejected before the (otherwise undefined) conversion.
  ExpectPresetError([](auto& j) { j["luts"]["grid"]["n_theta"] = 1e300; }, "luts.grid");
  ExpectPresetError([](auto& j) { j["luts"]["grid"]["n_gamma"] = -1e300; }, "luts.grid");
}

TEST(JsonSchema, NearestNameFindsTyposNotStrangers) {
  const std::vector<std::string> names = {"haziness_g", "sun_illuminance", "ground_albedo", "center", "cameras"};
  EXPECT_EQ(NearestName("hazines_g", names), "haziness_g");    // a dropped letter
  EXPECT_EQ(NearestName("haizness_g", names), "haziness_g");   // a swapped pair
  EXPECT_EQ(NearestName("haziness", names), "haziness_g");     // a prefix
  EXPECT_EQ(NearestName("centre", names), "center");           // British spelling
  EXPECT_EQ(NearestName("groundalbedo", names), "ground_albedo");
  EXPECT_EQ(NearestName("exposure", names), "");                // nothing near: no guess
  EXPECT_EQ(NearestName(std::string(5000, 'a'), names), "");    // bounded work on hostile keys
}

TEST(PresetIo, NanTexelAndCorruptJsonAreRejected) {
  ScratchDir dir("nan");
  render::Preset p = testing::RandomPreset(2, render::ModelVariant::kFfxv);
  p.luts.mie[40] = std::nanf("");
  EXPECT_THROW(render::SavePreset(p, dir / "p.json"), Error);
  EXPECT_EQ(dir.CountEntries(), 0);  // nothing written
  p.luts.mie[40] = 1.0f;
  p.haziness_g = std::nan("");
  try {
    render::ValidatePreset(p, "test");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("haziness_g"), std::string::npos);
  }
  testing::WriteText(dir / "corrupt.json", "{\"format\": \"skycal-preset\", ");
  try {
    render::LoadPreset(dir / "corrupt.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos);
  }
  EXPECT_THROW(render::LoadPreset(dir / "absent.json"), Error);
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

TEST(ExrIo, ExtraPlanesRoundTrip) {
  testing::ScratchDir dir("planes");
  ImageRGB img(16, 8);
  for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<float>(i);
  ExrPlane mask{"mask.valid", std::vector<float>(16 * 8, 1.0f)};
  mask.values[5] = 0.0f;
  WriteExrRGBWithPlanes(dir / "p.exr", img, {mask}, {});
  int w = 0, h = 0;
  const std::vector<float> back = ReadExrChannel(dir / "p.exr", "mask.valid", &w, &h);
  EXPECT_EQ(w, 16);
  EXPECT_EQ(h, 8);
  EXPECT_EQ(back, mask.values);
  EXPECT_EQ(ReadExrRGB(dir / "p.exr").image.pixels, img.pixels);
  EXPECT_THROW(ReadExrChannel(dir / "p.exr", "mask.cloud", &w, &h), Error);
  EXPECT_THROW(WriteExrRGBWithPlanes(dir / "q.exr", img, {{"R", mask.values}}, {}), Error);
  EXPECT_EQ(dir.CountEntries(), 1);
}

// FIPS 180-2 appendix B test vectors (one block, empty, two blocks, a million 'a'), and a
// file hashed the same as its bytes.
TEST(Sha256, FipsVectorsAndFiles) {
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  ScratchDir dir("sha256");
  const std::string bytes("binary\0bytes\xff", 14);
  {
    std::ofstream f(dir / "b.bin", std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  EXPECT_EQ(Sha256OfFile(dir / "b.bin"), Sha256Hex(bytes));
  EXPECT_THROW(Sha256OfFile(dir / "missing.bin"), Error);
}

}  // namespace
}  // namespace skycal
