// Camera RAW through LibRaw (libraw_r, the thread-safe build: LoadBrackets decodes brackets
// on several threads, one LibRaw object each). LibRaw unpacks the file and demosaics it
// (dcraw_process); everything that would make the result non-linear or image-dependent is
// switched off (see Configure); the colour matrix is NOT applied by LibRaw but returned, so
// the merge runs in camera RGB and the matrix is applied to the merged radiance in floating
// point (reasons at CameraToRec709).
#include "skycal/capture/raw_decode.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include <libraw/libraw.h>

#include "skycal/core/error.h"

namespace skycal::capture {
namespace {

// LibRaw reports corrupt data through this callback (offset -1: end of file) and carries on;
// the decoder records it and refuses the image afterwards rather than returning garbage.
struct DataErrors {
  int count = 0;
  bool eof = false;
  long long first_offset = -1;
};

void OnDataError(void* data, const char* /*file*/, const int offset) {
  auto* e = static_cast<DataErrors*>(data);
  if (e->count++ == 0) e->first_offset = offset;
  if (offset < 0) e->eof = true;
}

std::string LibRawWhy(int rc) { return std::string("LibRaw ") + LibRaw::version() + ": " + libraw_strerror(rc); }

// The settings of a linear decode (LibRaw's imgdata.params, dcraw's flags in brackets).
void Configure(libraw_output_params_t& p) {
  p.output_color = 0;            // raw colour (-o 0): camera RGB, the matrix is ours
  p.use_camera_wb = 0;           // no as-shot white balance (-w): sky colour is the measurement
  p.use_auto_wb = 0;             // no grey-world balance (-a)
  for (float& m : p.user_mul) m = 1.0f;  // unit channel multipliers (-r 1 1 1 1): code = (raw - black) / (white - black)
  p.highlight = 0;               // clip at the white level (-H 0); clipped photosites are marked, not reconstructed
  p.no_auto_bright = 1;          // no histogram-based brightening (-W)
  p.gamm[0] = p.gamm[1] = 1.0;   // linear (-g 1 1); only used by LibRaw's own image writers anyway
  p.output_bps = 16;             // (-4)
  p.adjust_maximum_thr = 0.0f;   // keep the file's white level: LibRaw would otherwise lower it to the
                                 // brightest pixel of this frame, a different scale per bracket
  p.user_black = -1;             // black level from the file (subtracted)
  p.user_sat = -1;               // white level from the file
  p.user_flip = -1;              // orientation from the file (applied by us, with the mask)
  p.half_size = 0;
  p.four_color_rgb = 0;
  p.use_fuji_rotate = 0;         // no 45-degree SuperCCD rotation (refused instead)
  p.user_qual = 3;               // AHD demosaic (Hirakawa & Parks 2005)
  p.med_passes = 0;
  p.threshold = 0.0f;            // no wavelet denoise
  p.exp_correc = 0;
  p.green_matching = 0;
  p.no_auto_scale = 0;
  p.no_interpolation = 0;
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

double Known(float v) { return v > 0.0f && std::isfinite(v) ? static_cast<double>(v) : NAN; }

// Why LibRaw found no image in a file: most RAW formats (DNG, CR2, NEF, ARW, PEF, ...) are
// TIFF-based, and a file cut short or overwritten loses the directory that TIFF's header
// points to; said so when the header points past the end. Otherwise: a format LibRaw does
// not decode (or not a RAW file).
std::string UnsupportedWhy(const std::string& path, int rc) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  unsigned char h[8] = {};
  std::ifstream f(path, std::ios::binary);
  if (!ec && f.read(reinterpret_cast<char*>(h), 8)) {
    const bool le = h[0] == 'I' && h[1] == 'I' && h[2] == 42 && h[3] == 0;
    const bool be = h[0] == 'M' && h[1] == 'M' && h[2] == 0 && h[3] == 42;
    const unsigned long long ifd = le ? (h[4] | h[5] << 8 | h[6] << 16 | static_cast<unsigned long long>(h[7]) << 24)
                                      : (static_cast<unsigned long long>(h[4]) << 24 | h[5] << 16 | h[6] << 8 | h[7]);
    if ((le || be) && ifd + 2 > size)
      return "truncated or corrupt: its TIFF header points to a directory at byte " + std::to_string(ifd) +
             ", past the end of the file (" + std::to_string(size) + " bytes)";
  }
  return "not a camera RAW file LibRaw decodes (unsupported format or compression, or not a RAW file; " +
         LibRawWhy(rc) + ")";
}

// Opens `path` into `raw`: the file exists, LibRaw knows its format and found an image.
void Open(LibRaw& raw, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": no such file (reading camera RAW)");
  if (std::filesystem::file_size(path, ec) == 0) throw Error(path + ": empty file (0 bytes), not a camera RAW");
  const int rc = raw.open_file(path.c_str());
  if (rc == LIBRAW_FILE_UNSUPPORTED) throw Error(path + ": " + UnsupportedWhy(path, rc));
  if (rc != LIBRAW_SUCCESS) throw Error(path + ": cannot read camera RAW (" + LibRawWhy(rc) + ")");
}

RawMetadata MetadataOf(const LibRaw& raw) {
  const libraw_data_t& d = raw.imgdata;
  RawMetadata m;
  m.make = d.idata.make;
  m.model = d.idata.model;
  m.unique_camera_model = d.color.UniqueCameraModel;
  m.lens = d.lens.Lens[0] ? d.lens.Lens : d.lens.makernotes.Lens;
  m.lens_make = d.lens.LensMake;
  m.focal_length_mm = Known(d.other.focal_len);
  m.exposure_time_s = Known(d.other.shutter);
  m.f_number = Known(d.other.aperture);
  m.iso = Known(d.other.iso_speed);
  m.dng_version = static_cast<int>(d.idata.dng_version);
  const unsigned filters = d.idata.filters;
  m.format = m.dng_version ? "dng" : filters == LIBRAW_XTRANS ? "x-trans" : filters > 1000 ? "bayer" : "linear";
  return m;
}

// Layouts whose pixels we could not map back to photosites, or that carry no RGB colour.
void RefuseUnsupportedLayout(const LibRaw& raw, const std::string& path) {
  const libraw_data_t& d = raw.imgdata;
  auto refuse = [&](const std::string& why) {
    throw Error(path + ": unsupported camera RAW layout (" + why + "; " + d.idata.make + " " + d.idata.model + ")");
  };
  if (d.idata.is_foveon) refuse("Foveon X3 sensor");
  if (d.rawdata.ioparams.fuji_width) refuse("Fuji SuperCCD 45-degree photosite layout");
  if (d.idata.colors != 3) refuse(std::to_string(d.idata.colors) + " colour channels, expected RGB");
  if (d.idata.filters != 0 && d.idata.filters != LIBRAW_XTRANS && d.idata.filters < 1000) refuse("colour filter pattern code " + std::to_string(d.idata.filters));
  if (std::fabs(d.sizes.pixel_aspect - 1.0) > 1e-3) refuse("non-square pixels, aspect " + std::to_string(d.sizes.pixel_aspect));
  if (!d.rawdata.raw_image && !d.rawdata.color4_image && !d.rawdata.color3_image)
    refuse("floating-point or otherwise unpacked-as-float raw data");
  if (d.rawdata.raw_image && d.idata.filters == 0) refuse("a single-channel image without a colour filter pattern");
}

// Per photosite (sensor orientation, the output's height x width): at or above the white
// level in any channel. A mosaic's mark is dilated by `radius` (the demosaic's footprint:
// AHD interpolates from +-2 photosites, then the red/blue differences from +-1 more).
std::vector<uint8_t> SaturatedPhotosites(const LibRaw& raw, int radius) {
  const libraw_rawdata_t& rd = raw.imgdata.rawdata;
  const int w = raw.imgdata.sizes.width, h = raw.imgdata.sizes.height;
  const int top = rd.sizes.top_margin, left = rd.sizes.left_margin;
  const unsigned white = rd.color.maximum;
  std::vector<uint8_t> s(static_cast<size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t ry = static_cast<size_t>(y + top), rx = static_cast<size_t>(x + left);
      bool sat = false;
      if (rd.raw_image) {
        sat = rd.raw_image[ry * (rd.sizes.raw_pitch / 2) + rx] >= white;
      } else if (rd.color4_image) {
        const ushort* p = rd.color4_image[ry * (rd.sizes.raw_pitch / 8) + rx];
        sat = p[0] >= white || p[1] >= white || p[2] >= white;
      } else {
        const ushort* p = rd.color3_image[ry * (rd.sizes.raw_pitch / 6) + rx];
        sat = p[0] >= white || p[1] >= white || p[2] >= white;
      }
      s[static_cast<size_t>(y) * w + x] = sat;
    }
  }
  if (radius <= 0) return s;
  // Separable max filter: rows, then columns.
  std::vector<uint8_t> t(s.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (s[static_cast<size_t>(y) * w + x])
        for (int dx = std::max(0, x - radius); dx <= std::min(w - 1, x + radius); ++dx) t[static_cast<size_t>(y) * w + dx] = 1;
  std::fill(s.begin(), s.end(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (t[static_cast<size_t>(y) * w + x])
        for (int dy = std::max(0, y - radius); dy <= std::min(h - 1, y + radius); ++dy) s[static_cast<size_t>(dy) * w + x] = 1;
  return s;
}

// Camera RGB -> linear Rec.709 from LibRaw's rgb_cam (camera RGB, balanced by the daylight
// multipliers pre_mul, -> sRGB primaries, D65) and pre_mul, both computed by LibRaw's
// cam_xyz_coeff from one XYZ->camera matrix (the DNG's ColorMatrix, else its table's):
// M = rgb_cam * diag(pre_mul / pre_mul[green]). This is the matrix LibRaw's own
// output_color = 1 (sRGB primaries = Rec.709, linear with gamma 1/1) would apply with
// use_camera_wb = 0, but applied by the pipeline after the merge, in float: LibRaw's
// conversion clips to 0..65535 (losing negative and above-white values of saturated
// colours) and would mix a clipped channel into all three before the merge could drop it.
std::array<double, 9> CameraToRec709(const libraw_colordata_t& c) {
  std::array<double, 9> m{};
  const double g = c.pre_mul[1] > 0.0f ? c.pre_mul[1] : 1.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[3 * i + j] = c.rgb_cam[i][j] * (c.pre_mul[j] > 0.0f ? c.pre_mul[j] : 1.0) / g;
  return m;
}

// dcraw's flip_index: output pixel (row, col) of the oriented image -> sensor pixel.
size_t FlipIndex(int flip, int row, int col, int sensor_w, int sensor_h) {
  if (flip & 4) std::swap(row, col);
  if (flip & 2) row = sensor_h - 1 - row;
  if (flip & 1) col = sensor_w - 1 - col;
  return static_cast<size_t>(row) * sensor_w + col;
}

// LibRaw's processed image (sensor orientation, RGB in channels 0..2) and the saturation
// mask, rotated to the file's orientation, into a 16-bit linear BracketImage.
BracketImage OrientedImage(const LibRaw& raw, const std::vector<uint8_t>& saturated, int flip) {
  const int sw = raw.imgdata.sizes.iwidth, sh = raw.imgdata.sizes.iheight;
  BracketImage img;
  img.bits = 16;
  img.linear = true;
  img.width = (flip & 4) ? sh : sw;
  img.height = (flip & 4) ? sw : sh;
  img.rgb.resize(static_cast<size_t>(img.width) * img.height * 3);
  img.saturated.resize(static_cast<size_t>(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const size_t s = FlipIndex(flip, y, x, sw, sh), o = static_cast<size_t>(y) * img.width + x;
      for (int c = 0; c < 3; ++c) img.rgb[3 * o + c] = raw.imgdata.image[s][c];
      img.saturated[o] = saturated[s];
    }
  return img;
}

// Unpacks (catching truncation and corrupt data) and demosaics.
void UnpackAndProcess(LibRaw& raw, const std::string& path, DataErrors& errors) {
  int rc = raw.unpack();
  if (errors.eof || rc == LIBRAW_IO_ERROR)
    throw Error(path + ": truncated camera RAW (the pixel data ends early; " + LibRawWhy(LIBRAW_IO_ERROR) + ")");
  if (rc != LIBRAW_SUCCESS) throw Error(path + ": cannot decode camera RAW pixel data (" + LibRawWhy(rc) + ")");
  if (errors.count > 0)
    throw Error(path + ": corrupt camera RAW pixel data (LibRaw reported " + std::to_string(errors.count) +
                " decoding error(s), the first at byte " + std::to_string(errors.first_offset) + ")");
  RefuseUnsupportedLayout(raw, path);
  rc = raw.dcraw_process();
  if (rc != LIBRAW_SUCCESS) throw Error(path + ": cannot process camera RAW (" + LibRawWhy(rc) + ")");
  const libraw_image_sizes_t& s = raw.imgdata.sizes;
  if (s.iwidth != s.width || s.iheight != s.height || !raw.imgdata.image)
    throw Error(path + ": unsupported camera RAW layout (processed size " + std::to_string(s.iwidth) + "x" +
                std::to_string(s.iheight) + " differs from the sensor's " + std::to_string(s.width) + "x" +
                std::to_string(s.height) + ")");
}

}  // namespace

bool IsRawPath(const std::string& path) {
  static const char* const kExtensions[] = {".dng", ".cr2", ".cr3", ".crw", ".nef", ".nrw", ".arw", ".srf",
                                            ".sr2", ".raf", ".orf", ".rw2", ".rwl", ".pef", ".srw", ".3fr",
                                            ".iiq", ".erf", ".kdc", ".dcr", ".mos", ".mrw", ".x3f", ".raw"};
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  return std::any_of(std::begin(kExtensions), std::end(kExtensions), [&](const char* e) { return ext == e; });
}

RawMetadata ReadRawMetadata(const std::string& path) {
  auto raw = std::make_unique<LibRaw>();  // ~1 MB of state: not on the stack
  Open(*raw, path);
  return MetadataOf(*raw);
}

RawImage ReadRawImage(const std::string& path) {
  auto raw = std::make_unique<LibRaw>();
  DataErrors errors;
  raw->set_dataerror_handler(&OnDataError, &errors);
  Configure(raw->imgdata.params);
  Open(*raw, path);
  RawImage r;
  r.metadata = MetadataOf(*raw);
  // Read before processing: scale_colors replaces pre_mul with user_mul.
  r.camera_to_rec709 = CameraToRec709(raw->imgdata.color);
  UnpackAndProcess(*raw, path, errors);
  const libraw_colordata_t& rc = raw->imgdata.rawdata.color;
  r.has_matrix = raw->imgdata.rawdata.ioparams.raw_color == 0;
  r.white_level = rc.maximum;
  r.black_level = rc.black + (rc.cblack[0] + rc.cblack[1] + rc.cblack[2] + rc.cblack[3]) / 4.0;
  if (!(r.white_level > r.black_level))
    throw Error(path + ": camera RAW white level " + std::to_string(rc.maximum) + " is not above its black level " +
                std::to_string(r.black_level));
  const unsigned filters = raw->imgdata.idata.filters;
  const int radius = filters == 0 ? 0 : filters == LIBRAW_XTRANS ? 6 : 3;
  r.flip = raw->imgdata.sizes.flip;
  r.image = OrientedImage(*raw, SaturatedPhotosites(*raw, radius), r.flip);
  for (uint8_t s : r.image.saturated) r.saturated_pixels += s;
  return r;
}

nlohmann::json RawMetadataToJson(const RawMetadata& m) {
  auto opt = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
  return {{"make", m.make},
          {"model", m.model},
          {"unique_camera_model", m.unique_camera_model},
          {"lens", m.lens},
          {"lens_make", m.lens_make},
          {"focal_length_mm", opt(m.focal_length_mm)},
          {"exposure_time_s", opt(m.exposure_time_s)},
          {"f_number", opt(m.f_number)},
          {"iso", opt(m.iso)},
          {"dng_version", m.dng_version},
          {"format", m.format}};
}

}  // namespace skycal::capture
