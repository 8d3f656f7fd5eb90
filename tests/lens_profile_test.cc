// Lens profiles through lensfun (capture/lens_profile.h), checked against the installed
// database's own coefficients (Debian liblensfun-data-v1, /usr/share/lensfun/version_1):
// the test reads them from the XML itself and applies lensfun's documented formulas
// independently of the module (which runs lensfun's lfModifier).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "skycal/capture/capture_pipeline.h"
#include "skycal/capture/exif_exposure.h"
#include "skycal/capture/lens_profile.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "test_util.h"

namespace skycal::capture {
namespace {

const std::string kDb = "/usr/share/lensfun/version_1/";

// The attribute `name` of the first line of `file` that contains every one of `needles`
// after the line containing `block` (the lens's <model>).
double XmlAttr(const std::string& file, const std::string& block, const std::vector<std::string>& needles,
               const std::string& name) {
  std::ifstream in(kDb + file);
  EXPECT_TRUE(in.good()) << kDb + file;
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.find("<model>" + block + "</model>") != std::string::npos) inside = true;
    if (inside && line.find("</lens>") != std::string::npos) break;
    bool all = inside;
    for (const auto& n : needles) all = all && line.find(n) != std::string::npos;
    std::smatch m;
    if (all && std::regex_search(line, m, std::regex(" " + name + "=\"([-0-9.eE]+)\"")))
      return std::stod(m[1].str());
  }
  ADD_FAILURE() << file << ": no " << name << " on a line with the given needles after " << block;
  return NAN;
}

// lensfun's vignetting radius (modifier.cpp "About coordinate systems": r = 1 at the image
// corner, distances between the outer pixel centres) for an image whose sensor is the
// calibration's (same crop factor and aspect ratio).
double VignettingRadius(int x, int y, int w, int h) {
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1);
  return std::hypot(x - cx, y - cy) / std::hypot(cx, cy);
}

double PaGain(const std::array<double, 3>& k, double r) {
  const double r2 = r * r;
  return 1.0 + k[0] * r2 + k[1] * r2 * r2 + k[2] * r2 * r2 * r2;
}

// A smooth non-flat linear image: a horizontal ramp times a vertical one, per channel.
ImageRGB Gradient(int w, int h) {
  ImageRGB img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = (0.2f + 0.8f * x / w) * (0.5f + 0.5f * y / h) * (1.0f + 0.5f * c);
  return img;
}

// Largest |a / b - 1| over the image.
double MaxRelativeError(const ImageRGB& a, const ImageRGB& b) {
  double e = 0.0;
  for (size_t i = 0; i < a.pixels.size(); ++i) e = std::max(e, std::abs(a.pixels[i] / b.pixels[i] - 1.0));
  return e;
}

LensQuery SamyangOnNex7(double f_number) {
  LensQuery q;
  q.camera_maker = "SONY";  // as the camera writes it
  q.camera_model = "NEX-7";
  q.lens_model = "Samyang 8mm f/2.8 UMC Fish-eye";
  q.focal_mm = 8.0;
  q.f_number = f_number;
  return q;
}

TEST(LensProfile, LookupByExifNamesGivesTheDatabaseEntryAndItsCoefficients) {
  const LensLookup r = FindLensProfile(SamyangOnNex7(4.0));
  ASSERT_TRUE(r.profile) << r.message;
  const LensProfile& p = *r.profile;
  EXPECT_EQ(p.camera_maker, "Sony");
  EXPECT_EQ(p.camera_model, "NEX-7");
  EXPECT_EQ(p.lens_model, "Samyang 8mm f/2.8 UMC Fish-eye");
  EXPECT_EQ(p.lens_type, "stereographic");
  ASSERT_TRUE(p.projection);
  EXPECT_EQ(*p.projection, LensModel::kStereographic);
  EXPECT_NEAR(p.crop_factor, 1.534, 1e-6);
  EXPECT_NEAR(p.real_focal_mm, 8.405, 1e-5);  // mil-samyang.xml:67 real-focal-length
  EXPECT_TRUE(p.missing.empty()) << p.missing.front();
  // mil-samyang.xml:57, the calibrated f/4 at infinity row: interpolation returns it.
  const std::string lens = "Samyang 8mm f/2.8 UMC Fish-eye";
  const std::vector<std::string> row = {"aperture=\"4\"", "distance=\"1000\""};
  ASSERT_TRUE(p.vignetting_k);
  EXPECT_NEAR((*p.vignetting_k)[0], XmlAttr("mil-samyang.xml", lens, row, "k1"), 1e-6);
  EXPECT_NEAR((*p.vignetting_k)[1], XmlAttr("mil-samyang.xml", lens, row, "k2"), 1e-6);
  EXPECT_NEAR((*p.vignetting_k)[2], XmlAttr("mil-samyang.xml", lens, row, "k3"), 1e-6);
  // mil-samyang.xml:50-51: ptlens distortion, poly3 TCA (lensfun's term order vr, vb, cr, cb, br, bb).
  ASSERT_EQ(p.distortion_model.value_or(""), "ptlens");
  EXPECT_NEAR(p.distortion_terms[0], XmlAttr("mil-samyang.xml", lens, {"<distortion"}, "a"), 1e-7);
  EXPECT_NEAR(p.distortion_terms[2], XmlAttr("mil-samyang.xml", lens, {"<distortion"}, "c"), 1e-7);
  ASSERT_EQ(p.tca_model.value_or(""), "poly3");
  EXPECT_NEAR(p.tca_terms[0], XmlAttr("mil-samyang.xml", lens, {"<tca"}, "vr"), 1e-7);
  EXPECT_NEAR(p.tca_terms[5], XmlAttr("mil-samyang.xml", lens, {"<tca"}, "bb"), 1e-9);
}

TEST(LensProfile, ALensWithoutTcaOrAnFNumberSaysWhatIsMissing) {
  LensQuery q;
  q.camera_maker = "NIKON CORPORATION";
  q.camera_model = "NIKON D800";
  q.lens_model = "Samyang 12mm f/2.8 Fish-Eye ED AS NCS";
  const LensLookup r = FindLensProfile(q);
  ASSERT_TRUE(r.profile) << r.message;
  EXPECT_EQ(r.profile->camera_model, "D800");
  EXPECT_DOUBLE_EQ(r.profile->focal_mm, 12.0);  // a fixed focal lens needs no EXIF focal length
  EXPECT_FALSE(r.profile->tca_model);
  EXPECT_FALSE(r.profile->vignetting_k);  // no f-number
  ASSERT_EQ(r.profile->missing.size(), 2u);
  EXPECT_NE(r.profile->missing[0].find("no TCA data"), std::string::npos) << r.profile->missing[0];
  EXPECT_NE(r.profile->missing[1].find("no f-number"), std::string::npos) << r.profile->missing[1];
}

// The EXIF spelling of a camera and a maker-style lens name (as an Olympus body writes them).
TEST(LensProfile, LookupByCameraSpellingPrefersTheExactModel) {
  LensQuery q;
  q.camera_maker = "OLYMPUS CORPORATION";
  q.camera_model = "E-M1";
  q.lens_model = "OLYMPUS M.8mm F1.8";
  q.focal_mm = 8.0;
  const LensLookup r = FindLensProfile(q);
  ASSERT_TRUE(r.profile) << r.message;
  EXPECT_EQ(r.profile->camera_model, "E-M1");  // not E-M1MarkII / E-M1MarkIII
  EXPECT_EQ(r.profile->lens_model, "Olympus M.Zuiko Digital ED 8mm f/1.8 Fisheye Pro");
  EXPECT_EQ(r.profile->lens_type, "equisolid");
  EXPECT_DOUBLE_EQ(r.profile->crop_factor, 2.0);
}

TEST(LensProfile, NoMatchNamesWhatWasSearchedAndTheClosestLenses) {
  LensQuery q;
  q.camera_maker = "Acme";
  q.camera_model = "SkyCam 1";
  q.lens_model = "Samyang 8mm f/2.8 UMC Fishy-eye";
  const LensLookup r = FindLensProfile(q);
  EXPECT_FALSE(r.profile);
  for (const char* s : {"'Acme' 'SkyCam 1'", "'Samyang 8mm f/2.8 UMC Fishy-eye'", "no camera matched", "no lens matched"})
    EXPECT_NE(r.message.find(s), std::string::npos) << s << " not in: " << r.message;
  ASSERT_FALSE(r.candidates.empty());
  EXPECT_EQ(r.candidates[0], "Samyang:Samyang 8mm f/2.8 UMC Fish-eye") << r.message;
  LensQuery none;
  none.camera_maker = "SONY";
  none.camera_model = "NEX-7";
  const LensLookup n = FindLensProfile(none);
  EXPECT_FALSE(n.profile);
  EXPECT_NE(n.message.find("camera found as 'Sony' 'NEX-7'; no lens named"), std::string::npos) << n.message;
}

TEST(LensProfile, ExplicitSpecSyntax) {
  LensQuery q;
  std::string why;
  ASSERT_TRUE(ParseLensProfileSpec("Samyang:Samyang 8mm f/2.8 UMC Fish-eye@Sony:NEX-7", &q, &why)) << why;
  EXPECT_EQ(q.lens_maker, "Samyang");
  EXPECT_EQ(q.lens_model, "Samyang 8mm f/2.8 UMC Fish-eye");
  EXPECT_EQ(q.camera_maker, "Sony");
  EXPECT_EQ(q.camera_model, "NEX-7");
  EXPECT_TRUE(q.explicit_spec);
  LensQuery bad;
  EXPECT_FALSE(ParseLensProfileSpec("Samyang 8mm", &bad, &why));
  EXPECT_NE(why.find("CaptureOptions::lens_profile = Samyang 8mm"), std::string::npos) << why;
  EXPECT_FALSE(ParseLensProfileSpec("Samyang:8mm@NEX-7", &bad, &why));
  EXPECT_FALSE(bad.explicit_spec);
}

// Vignetting by the database's own f/4 coefficients (read from the XML here), applied with
// lensfun's formula and normalisation, then removed by the module: the identity to float
// precision. Controls: the f/2.8 coefficients, and the radius normalised to half the
// shorter side instead of the half-diagonal, both leave errors far above it.
TEST(LensProfile, VignettingRoundTripAgainstTheDatabaseCoefficients) {
  const LensLookup r = FindLensProfile(SamyangOnNex7(4.0));
  ASSERT_TRUE(r.profile) << r.message;
  const std::string lens = "Samyang 8mm f/2.8 UMC Fish-eye";
  auto row = [&](const char* aperture) {
    const std::vector<std::string> n = {std::string("aperture=\"") + aperture + "\"", "distance=\"1000\""};
    return std::array<double, 3>{XmlAttr("mil-samyang.xml", lens, n, "k1"), XmlAttr("mil-samyang.xml", lens, n, "k2"),
                                 XmlAttr("mil-samyang.xml", lens, n, "k3")};
  };
  const int w = 600, h = 400;  // 3:2, the NEX-7's (and the calibration's) aspect ratio
  const ImageRGB truth = Gradient(w, h);
  auto vignetted = [&](const std::array<double, 3>& k, double shorter_side_norm) {
    ImageRGB img = truth;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double rad = VignettingRadius(x, y, w, h);
        if (shorter_side_norm) rad = std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) / (0.5 * (h - 1));
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(truth.at(x, y, c) * PaGain(k, rad));
      }
    return img;
  };
  const LensCorrections only_vignetting{true, false, false};
  ImageRGB img = vignetted(row("4"), false);
  const double before = MaxRelativeError(img, truth);
  const nlohmann::json applied = ApplyLensProfile(*r.profile, only_vignetting, &img);
  EXPECT_TRUE(applied["vignetting"].get<bool>());
  EXPECT_FALSE(applied["tca"].get<bool>());
  const double after = MaxRelativeError(img, truth);
  EXPECT_GT(before, 0.5);   // the corners lose more than half their light at f/4
  EXPECT_LT(after, 2e-6);   // float precision (lensfun evaluates the gain in float)
  ImageRGB wrong_k = vignetted(row("2.8"), false);
  ApplyLensProfile(*r.profile, only_vignetting, &wrong_k);
  EXPECT_GT(MaxRelativeError(wrong_k, truth), 0.05);
  ImageRGB wrong_norm = vignetted(row("4"), true);
  ApplyLensProfile(*r.profile, only_vignetting, &wrong_norm);
  EXPECT_GT(MaxRelativeError(wrong_norm, truth), 0.05);
  std::cout << "vignetting round trip: max relative error " << before << " before, " << after << " after\n";
}

// lensfun's unit of radius for TCA and distortion, pixels (modifier.cpp, lfModifier::lfModifier:
// NormScale = 2 / min(W-1, H-1) * coordinate_correction): the half-diagonal between the
// outer pixel centres over sqrt(1 + aspect^2), aspect the calibration's (3:2 where the XML
// gives none: database.cpp's default), scaled by the crop factors. Half the shorter side
// only when the image has the calibration's aspect ratio exactly (a 900x600 image's 899:599
// is 0.04% off, which moves a 28 px distortion by 0.03 px at the corners).
double LensfunUnit(int w, int h, const LensProfile& p) {
  const double aspect = p.calibration_aspect_ratio;
  EXPECT_DOUBLE_EQ(aspect, 1.5);
  return 0.5 * std::hypot(w - 1.0, h - 1.0) / std::sqrt(1.0 + aspect * aspect) * p.crop_factor /
         p.calibration_crop_factor;
}

// TCA (lensfun poly3): the corrected radius r_u of red / blue was observed at r_d = r_u (b
// r_u^2 + c r_u + v), r in LensfunUnit.
double TcaScale(double b, double c, double v, double ru) { return b * ru * ru + c * ru + v; }

// A soft-edged checkerboard (edges about 2.5 px wide), continuous in x, y.
double Pattern(double x, double y) {
  const double k = 2.0 * M_PI / 48.0;
  return 0.5 + 0.4 * std::tanh(3.0 * std::sin(k * x)) * std::tanh(3.0 * std::sin(k * y));
}

// The radial displacement (pixels, + outward) of channel c of img against channel rc of ref
// in the outer ring of the image (r > 0.8 of the half-diagonal, the corners), by least
// squares on ref's gradient: X(p) = R(p - d r_hat)  =>  X - R = -d dR/dr. *known (may be
// null) receives the same weighted mean of known_px(r), the displacement put in at radius r
// (pixels).
template <class Known>
double RadialShift(const ImageRGB& img, int c, const ImageRGB& ref, int rc, Known known_px, double* known) {
  const int w = img.width, h = img.height;
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1), hd = std::hypot(cx, cy);
  double num = 0.0, den = 0.0, kn = 0.0;
  for (int y = 4; y < h - 4; ++y)
    for (int x = 4; x < w - 4; ++x) {
      const double dx = x - cx, dy = y - cy, rr = std::hypot(dx, dy);
      if (rr < 0.8 * hd) continue;
      const double gx = 0.5 * (ref.at(x + 1, y, rc) - ref.at(x - 1, y, rc));
      const double gy = 0.5 * (ref.at(x, y + 1, rc) - ref.at(x, y - 1, rc));
      const double gr = (gx * dx + gy * dy) / rr;
      num += (img.at(x, y, c) - ref.at(x, y, rc)) * gr;
      den += gr * gr;
      kn += known_px(rr) * gr * gr;
    }
  if (known) *known = kn / den;
  return -num / den;
}

TEST(LensProfile, TcaCorrectionAlignsTheChannelsToSubPixel) {
  LensQuery q;  // no camera: the lens's calibration sensor (crop 1.534, 3:2)
  q.lens_maker = "Sigma";
  q.lens_model = "Sigma 4.5mm f/2.8 EX DC HSM circular fisheye";
  const LensLookup r = FindLensProfile(q);
  ASSERT_TRUE(r.profile) << r.message;
  ASSERT_EQ(r.profile->tca_model.value_or(""), "poly3");
  // slr-sigma.xml:3221 (read here): br, vr, bb, vb; cr = cb = 0.
  const std::string lens = "Sigma 4.5mm f/2.8 EX DC HSM circular fisheye";
  const double br = XmlAttr("slr-sigma.xml", lens, {"<tca"}, "br"), vr = XmlAttr("slr-sigma.xml", lens, {"<tca"}, "vr");
  const double bb = XmlAttr("slr-sigma.xml", lens, {"<tca"}, "bb"), vb = XmlAttr("slr-sigma.xml", lens, {"<tca"}, "vb");
  const int w = 1200, h = 800;
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1), unit = LensfunUnit(w, h, *r.profile);
  ImageRGB img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double rd = std::hypot(x - cx, y - cy) / unit;
      img.at(x, y, 1) = static_cast<float>(Pattern(x, y));
      for (int c : {0, 2}) {
        const double b = c == 0 ? br : bb, v = c == 0 ? vr : vb;
        double ru = rd;  // observed at rd: the scene point at ru with ru * scale(ru) = rd (Newton)
        for (int i = 0; i < 20 && rd > 0; ++i) ru -= (ru * TcaScale(b, 0, v, ru) - rd) / (3 * b * ru * ru + v);
        const double s = rd > 0 ? ru / rd : 1.0;
        img.at(x, y, c) = static_cast<float>(Pattern(cx + (x - cx) * s, cy + (y - cy) * s));
      }
    }
  // The displacement put in at radius r (px): r_d - r_u, r_u solving r_u scale(r_u) = r_d.
  auto known = [&](double b, double v) {
    return [=](double rd_px) {
      const double rd = rd_px / unit;
      double ru = rd;
      for (int i = 0; i < 20; ++i) ru -= (ru * TcaScale(b, 0, v, ru) - rd) / (3 * b * ru * ru + v);
      return (rd - ru) * unit;
    };
  };
  double red_known = 0.0, blue_known = 0.0;
  const double red_before = RadialShift(img, 0, img, 1, known(br, vr), &red_known);
  const double blue_before = RadialShift(img, 2, img, 1, known(bb, vb), &blue_known);
  const nlohmann::json applied = ApplyLensProfile(*r.profile, {false, true, false}, &img);
  EXPECT_TRUE(applied["tca"].get<bool>());
  EXPECT_FALSE(applied["distortion"].get<bool>());
  auto none = [](double) { return 0.0; };
  const double red_after = RadialShift(img, 0, img, 1, none, nullptr), blue_after = RadialShift(img, 2, img, 1, none, nullptr);
  std::cout << "TCA radial shift against green (px, corners r > 0.8 half-diagonal): red " << red_before << " (put in "
            << red_known << ") -> " << red_after << ", blue " << blue_before << " (put in " << blue_known << ") -> "
            << blue_after << "\n";
  // The measurement sees what was put in (red about 1.1 px inward at the corners)...
  EXPECT_LT(red_known, -1.0);
  EXPECT_NEAR(red_before, red_known, 0.05);
  EXPECT_NEAR(blue_before, blue_known, 0.05);
  // ...and the correction takes it out to 0.02 px.
  EXPECT_LT(std::abs(red_after), 0.02);
  EXPECT_LT(std::abs(blue_after), 0.02);
}

// Distortion (lensfun ptlens, mil-samyang.xml:50, read here): the observed radius r_d = r_u (a
// r_u^3 + b r_u^2 + c r_u + 1 - a - b - c), r in LensfunUnit. A checkerboard put through it
// (about 28 px inward at the corners) and corrected by the module sits where the undistorted
// one does, to 0.02 px.
TEST(LensProfile, DistortionCorrectionRestoresTheIdealProjection) {
  const LensLookup r = FindLensProfile(SamyangOnNex7(4.0));
  ASSERT_TRUE(r.profile) << r.message;
  const std::string lens = "Samyang 8mm f/2.8 UMC Fish-eye";
  const double a = XmlAttr("mil-samyang.xml", lens, {"<distortion"}, "a");
  const double b = XmlAttr("mil-samyang.xml", lens, {"<distortion"}, "b");
  const double c = XmlAttr("mil-samyang.xml", lens, {"<distortion"}, "c");
  const double d = 1.0 - a - b - c;
  const int w = 900, h = 600;
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1), unit = LensfunUnit(w, h, *r.profile);
  auto distort = [&](double ru) { return ru * (((a * ru + b) * ru + c) * ru + d); };
  ImageRGB observed(w, h), truth(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double rd = std::hypot(x - cx, y - cy) / unit;
      double ru = rd;  // the ideal radius seen at rd (Newton on distort(ru) = rd)
      for (int i = 0; i < 30 && rd > 0; ++i) {
        const double e = 1e-6, f = distort(ru) - rd, df = (distort(ru + e) - distort(ru - e)) / (2 * e);
        ru -= f / df;
      }
      const double s = rd > 0 ? ru / rd : 1.0;
      for (int ch = 0; ch < 3; ++ch) {
        observed.at(x, y, ch) = static_cast<float>(Pattern(cx + (x - cx) * s, cy + (y - cy) * s));
        truth.at(x, y, ch) = static_cast<float>(Pattern(x, y));
      }
    }
  auto known = [&](double rd_px) {
    const double rd = rd_px / unit;
    double ru = rd;
    for (int i = 0; i < 30; ++i) {
      const double e = 1e-6, f = distort(ru) - rd, df = (distort(ru + e) - distort(ru - e)) / (2 * e);
      ru -= f / df;
    }
    return (rd - ru) * unit;
  };
  double put_in = 0.0;
  auto none = [](double) { return 0.0; };
  const double before = RadialShift(observed, 1, truth, 1, known, &put_in);
  ImageRGB img = observed;
  const nlohmann::json applied = ApplyLensProfile(*r.profile, {false, false, true}, &img);
  EXPECT_TRUE(applied["distortion"].get<bool>());
  EXPECT_FALSE(applied["tca"].get<bool>());
  double after = 0.0;
  for (int ch = 0; ch < 3; ++ch) after = std::max(after, std::abs(RadialShift(img, ch, truth, ch, none, nullptr)));
  std::cout << "distortion radial shift against the ideal projection (px, corners): " << before << " (put in "
            << put_in << ") -> " << after << "\n";
  EXPECT_LT(put_in, -20.0);  // barrel: the corners are observed inward
  EXPECT_LT(after, 0.02);  // with r = 1 at half the shorter side instead of LensfunUnit: 0.033
}

TEST(LensProfile, TheImageCircleFromTheFocalLength) {
  const LensLookup r = FindLensProfile(SamyangOnNex7(4.0));
  ASSERT_TRUE(r.profile) << r.message;
  const int w = 6000, h = 4000;
  LensParams lens;  // equisolid, 180 degrees
  nlohmann::json report;
  LensFromProfile(*r.profile, w, h, false, false, false, false, false, &lens, &report);
  EXPECT_EQ(lens.model, LensModel::kStereographic);
  EXPECT_DOUBLE_EQ(lens.center_x, 2999.5);
  // f_px = f_real * crop * half-diagonal / 21.633 mm = 8.405 * 1.534 * 3604.8 / 21.633.
  const double f_px = 8.405 * 1.534 * 0.5 * std::hypot(w - 1.0, h - 1.0) / 21.633307652783937;
  EXPECT_NEAR(report["focal_px"].get<double>(), f_px, 1e-3);
  // 2 f tan(45 deg) is beyond the corner: the fov is narrowed to what the corner sees.
  EXPECT_NEAR(lens.radius_px, 0.5 * std::hypot(w - 1.0, h - 1.0), 1e-6);
  EXPECT_NEAR(lens.fov_deg, 4.0 * std::atan(lens.radius_px / (2.0 * f_px)) * 180.0 / M_PI, 1e-6);
  std::string why;
  EXPECT_TRUE(lens.IsValid(&why, w, h)) << why;
  // Distortion corrected: lensfun's Hugin focal correction 1 - a - b - c (mil-samyang.xml:50).
  nlohmann::json corrected;
  LensParams lens2;
  LensFromProfile(*r.profile, w, h, true, false, false, true, true, &lens2, &corrected);
  EXPECT_NEAR(corrected["focal_px"].get<double>(), f_px / (1.0 - 0.02036 + 0.08028 - 0.01446), 1e-2);
  // A model given by hand that is not the lens's projection keeps its own circle.
  LensParams given;
  given.radius_px = 1234.0;
  nlohmann::json kept;
  LensFromProfile(*r.profile, w, h, false, true, false, false, false, &given, &kept);
  EXPECT_EQ(given.model, LensModel::kEquisolid);
  EXPECT_DOUBLE_EQ(given.radius_px, 1234.0);
  EXPECT_DOUBLE_EQ(given.fov_deg, 180.0);
  // A rectilinear lens has no lens.h model: the model and circle stay, and the report says so.
  LensQuery rect;
  rect.lens_maker = "Samyang";
  rect.lens_model = "Samyang 50mm f/1.4 AS UMC";
  const LensLookup rr = FindLensProfile(rect);
  ASSERT_TRUE(rr.profile) << rr.message;
  EXPECT_EQ(rr.profile->lens_type, "rectilinear");
  LensParams plain;
  plain.radius_px = 1234.0;
  nlohmann::json said;
  LensFromProfile(*rr.profile, w, h, true, false, false, false, false, &plain, &said);
  EXPECT_EQ(plain.model, LensModel::kEquisolid);
  EXPECT_DOUBLE_EQ(plain.radius_px, 1234.0);
  EXPECT_NE(said["projection"].get<std::string>().find("'rectilinear' has no lens model"), std::string::npos) << said;
}

// --- Through the capture pipeline ---------------------------------------------------------------

// Two JPEG brackets (1/100 s, 1/50 s) of a flat grey field as the Samyang 8 mm on a NEX-7
// records it at f/4: darkened by the database's f/4 vignetting (read from the XML), tagged
// with the camera, lens, focal length and f-number in EXIF.
std::vector<std::string> VignettedFlatBrackets(const testing::ScratchDir& dir, bool tag_names) {
  const std::string lens = "Samyang 8mm f/2.8 UMC Fish-eye";
  const std::vector<std::string> row = {"aperture=\"4\"", "distance=\"1000\""};
  const std::array<double, 3> k = {XmlAttr("mil-samyang.xml", lens, row, "k1"),
                                   XmlAttr("mil-samyang.xml", lens, row, "k2"),
                                   XmlAttr("mil-samyang.xml", lens, row, "k3")};
  const int w = 300, h = 200;
  std::vector<std::string> paths;
  for (int i = 0; i < 2; ++i) {
    cv::Mat img(h, w, CV_8UC3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double v = 100.0 * (i + 1) * PaGain(k, VignettingRadius(x, y, w, h));
        img.at<cv::Vec3b>(y, x) = cv::Vec3b::all(static_cast<unsigned char>(std::lround(v)));
      }
    paths.push_back(dir / ("flat_" + std::to_string(i) + ".jpg"));
    EXPECT_TRUE(cv::imwrite(paths.back(), img, {cv::IMWRITE_JPEG_QUALITY, 100}));
    ExifExposure e;
    e.f_number = 4.0;
    WriteExifExposure(paths.back(), e);
    if (tag_names) {
      LensQuery q = SamyangOnNex7(4.0);
      WriteLensQuery(paths.back(), q);
    }
  }
  return paths;
}

CaptureOptions FlatCapture(const std::vector<std::string>& brackets, const std::string& out) {
  CaptureOptions o;
  o.brackets = brackets;
  o.exposure_times_s = {0.01, 0.02};
  o.merge.response = ResponseModel::kLinear;
  o.width = 128;
  o.height = 64;
  o.out = out;
  o.verbose = false;
  return o;
}

// Coefficient of variation of the frame's covered pixels (green channel).
double FrameVariation(const std::string& path) {
  const ExrRGB f = ReadExrRGB(path);
  double s = 0.0, s2 = 0.0, n = 0.0;
  for (size_t i = 0; i < f.image.pixels.size(); i += 3) {
    const double v = f.image.pixels[i + 1];
    if (!(v > 0.0)) continue;
    s += v, s2 += v * v, n += 1.0;
  }
  const double mean = s / n;
  return std::sqrt(std::max(0.0, s2 / n - mean * mean)) / mean;
}

TEST(LensProfileCapture, TheExifProfileFlattensAVignettedFlatField) {
  testing::ScratchDir dir("lens-profile-capture");
  const auto brackets = VignettedFlatBrackets(dir, true);
  const std::string lens = "Samyang 8mm f/2.8 UMC Fish-eye";
  ASSERT_EQ(ReadLensQuery(brackets[0]).lens_model, lens);
  CaptureOptions with = FlatCapture(brackets, dir / "with.exr");
  const nlohmann::json j = RunCapturePipeline(with);
  const nlohmann::json& lp = j["lens_profile"];
  EXPECT_TRUE(lp["used"].get<bool>()) << lp.dump();
  EXPECT_EQ(lp["source"], "EXIF");
  EXPECT_EQ(lp["lens"], "Samyang:" + lens);
  EXPECT_EQ(lp["camera"], "Sony:NEX-7");
  for (const char* k : {"vignetting", "tca", "distortion"}) EXPECT_TRUE(lp["applied"][k].get<bool>()) << k;
  EXPECT_EQ(lp["unwrap"]["projection"], "stereographic");
  EXPECT_GT(j["valid_pixels"].get<long long>(), 2000);  // the measured plane follows the corrected geometry
  CaptureOptions without = FlatCapture(brackets, dir / "without.exr");
  without.lens_profile = "none";
  const nlohmann::json n = RunCapturePipeline(without);
  EXPECT_TRUE(n["lens_profile"].is_null());
  const double cv_with = FrameVariation(dir / "with.exr"), cv_without = FrameVariation(dir / "without.exr");
  std::cout << "flat field through capture: variation " << cv_without << " without the profile, " << cv_with
            << " with it\n";
  EXPECT_GT(cv_without, 0.05);  // the inscribed circle of the default lens: the corners' falloff is outside it
  EXPECT_LT(cv_with, 0.005);
}

TEST(LensProfileCapture, AnExplicitProfileThatMatchesNothingIsAnErrorNamingTheClosest) {
  testing::ScratchDir dir("lens-profile-explicit");
  const auto brackets = VignettedFlatBrackets(dir, false);
  CaptureOptions o = FlatCapture(brackets, dir / "frame.exr");
  o.lens_profile = "Samyang:Samyang 8mm f/2.8 UMC Fishy-eye";
  try {
    RunCapturePipeline(o);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("CaptureOptions::lens_profile = Samyang:Samyang 8mm f/2.8 UMC Fishy-eye"), std::string::npos) << m;
    EXPECT_NE(m.find("closest lenses in the database: 'Samyang:Samyang 8mm f/2.8 UMC Fish-eye'"), std::string::npos) << m;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "frame.exr"));
  // Without names in EXIF and no explicit profile: on without one, saying why.
  CaptureOptions plain = FlatCapture(brackets, dir / "plain.exr");
  const nlohmann::json j = RunCapturePipeline(plain);
  EXPECT_FALSE(j["lens_profile"]["used"].get<bool>());
  EXPECT_NE(j["lens_profile"]["reason"].get<std::string>().find("no camera or lens names"), std::string::npos);
  // The explicit name works where EXIF has none (the lens's calibration sensor then).
  CaptureOptions named = FlatCapture(brackets, dir / "named.exr");
  named.lens_profile = "Samyang:Samyang 8mm f/2.8 UMC Fish-eye";
  const nlohmann::json k = RunCapturePipeline(named);
  EXPECT_EQ(k["lens_profile"]["source"], "CaptureOptions::lens_profile");
  EXPECT_TRUE(k["lens_profile"]["applied"]["vignetting"].get<bool>());
  EXPECT_LT(FrameVariation(dir / "named.exr"), 0.005);
}

TEST(LensProfileCapture, HandGivenValuesOverrideAndMissingDataIsListedAsSkipped) {
  testing::ScratchDir dir("lens-profile-override");
  const auto brackets = VignettedFlatBrackets(dir, true);
  CaptureOptions o = FlatCapture(brackets, dir / "frame.exr");
  o.vignetting_given = true;  // zeros: no vignetting, by hand
  o.lens_model_given = true;  // equisolid, by hand
  const nlohmann::json j = RunCapturePipeline(o);
  const nlohmann::json& lp = j["lens_profile"];
  EXPECT_FALSE(lp["applied"]["vignetting"].get<bool>());
  EXPECT_TRUE(lp["applied"]["tca"].get<bool>());
  EXPECT_EQ(lp["overridden"][0], "vignetting: CaptureOptions::lens.vignetting given");
  EXPECT_EQ(lp["unwrap"]["projection"], "kept CaptureOptions::lens.model = equisolid (given)");
  EXPECT_FALSE(lp["unwrap"].contains("radius_px"));  // equisolid is not this lens's projection
  EXPECT_GT(FrameVariation(dir / "frame.exr"), 0.05);  // the vignetting stays in
  // A lens whose profile has no TCA: said in lens_profile.missing and under skipped.
  CaptureOptions no_tca = FlatCapture(brackets, dir / "no_tca.exr");
  no_tca.lens_profile = "Samyang:Samyang 12mm f/2.8 Fish-Eye ED AS NCS";
  const nlohmann::json k = RunCapturePipeline(no_tca);
  EXPECT_FALSE(k["lens_profile"]["applied"]["tca"].get<bool>());
  EXPECT_TRUE(k["lens_profile"]["applied"]["vignetting"].get<bool>());
  EXPECT_EQ(k["lens_profile"]["focal_mm"], 12.0);  // the prime's, not the EXIF's 8 mm (said in notes)
  EXPECT_EQ(k["lens_profile"]["notes"][0], "focal length: EXIF says 8 mm, this lens is a 12 mm prime; used 12 mm");
  bool listed = false;
  for (const auto& s : k["skipped"])
    listed = listed || (s["stage"] == "lens profile tca" &&
                        s["reason"] == "tca: the profile has no TCA data for this lens");
  EXPECT_TRUE(listed) << k["skipped"].dump();
}

}  // namespace
}  // namespace skycal::capture
