// Camera brackets from JPEG (libjpeg-turbo), PNG (libpng, core/png_io.h) and TIFF (libtiff),
// the field's own decoders, to 8- or 16-bit RGB with the EXIF orientation applied (exiv2).
// OpenCV's imread did this before; its imgcodecs module links GDAL and ~110 more libraries
// that every skycal process paid for at start-up (png_io.h). What imread did and this keeps:
// grey expanded to RGB, alpha dropped, 8 or 16 bits as stored, JPEG decoded with libjpeg's
// defaults (integer DCT, fancy upsampling), the EXIF orientation applied.
#include <cmath>
#include <csetjmp>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

// jpeglib.h needs size_t and FILE declared before it.
#include <jpeglib.h>
#include <tiffio.h>

#include "camera_image.h"
#include "exiv2_read.h"
#include "skycal/core/error.h"
#include "skycal/core/png_io.h"

namespace skycal::capture {
namespace {

// The file's first `n` bytes (fewer when it is shorter), or all of it (n = 0).
std::string ReadBytes(const std::string& path, size_t n = 0) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path + ": cannot read image (no such file, or not readable)");
  if (n == 0) return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  std::string head(n, '\0');
  f.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<size_t>(f.gcount()));
  return head;
}

BracketImage Sized(int width, int height, int bits) {
  BracketImage img;
  img.width = width;
  img.height = height;
  img.bits = bits;
  img.rgb.resize(static_cast<size_t>(width) * height * 3);
  return img;
}

// ---- JPEG -------------------------------------------------------------------------------

struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void OnJpegError(j_common_ptr cinfo) {
  auto* e = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}

// RefusedImageSize into a C buffer (DecodeJpeg's frame holds no C++ object: longjmp).
bool SizeAllowed(long long w, long long h, char* message, size_t n) {
  const std::string why = RefusedImageSize(w, h);
  std::snprintf(message, n, "%s", why.c_str());
  return why.empty();
}

// Between jpeg_create_decompress and jpeg_finish_decompress: false on a libjpeg error. Only
// plain pointers live in this frame (longjmp); the image is sized before any row is read.
bool DecodeJpeg(jpeg_decompress_struct* cinfo, JpegError* err, const std::string* bytes, BracketImage* img) {
  if (setjmp(err->jump)) return false;
  jpeg_mem_src(cinfo, reinterpret_cast<const unsigned char*>(bytes->data()), bytes->size());
  jpeg_read_header(cinfo, TRUE);
  if (cinfo->jpeg_color_space == JCS_CMYK || cinfo->jpeg_color_space == JCS_YCCK) {
    std::snprintf(err->message, sizeof err->message, "a CMYK JPEG (expected a camera's RGB or grey image)");
    return false;
  }
  cinfo->out_color_space = JCS_RGB;  // grey expanded, YCbCr converted
  if (!SizeAllowed(cinfo->image_width, cinfo->image_height, err->message, sizeof err->message)) return false;
  jpeg_start_decompress(cinfo);
  *img = Sized(static_cast<int>(cinfo->output_width), static_cast<int>(cinfo->output_height), 8);
  // The row buffer from libjpeg's own pool (freed by jpeg_destroy_decompress, longjmp or not).
  JSAMPARRAY row = (*cinfo->mem->alloc_sarray)(reinterpret_cast<j_common_ptr>(cinfo), JPOOL_IMAGE, cinfo->output_width * 3, 1);
  const size_t row_samples = static_cast<size_t>(cinfo->output_width) * 3;
  while (cinfo->output_scanline < cinfo->output_height) {
    const int y = static_cast<int>(cinfo->output_scanline);
    jpeg_read_scanlines(cinfo, row, 1);
    for (size_t i = 0; i < row_samples; ++i) img->rgb[img->index(0, y) + i] = row[0][i];
  }
  jpeg_finish_decompress(cinfo);
  return true;
}

BracketImage ReadJpeg(const std::string& path, const std::string& bytes) {
  jpeg_decompress_struct cinfo;
  JpegError err;
  err.message[0] = '\0';
  cinfo.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = OnJpegError;
  err.mgr.output_message = [](j_common_ptr) {};  // warnings (corrupt data recovered) stay quiet
  jpeg_create_decompress(&cinfo);
  BracketImage img;
  const bool ok = DecodeJpeg(&cinfo, &err, &bytes, &img);
  jpeg_destroy_decompress(&cinfo);
  if (!ok) throw Error(path + ": cannot read image (JPEG: " + err.message + ")");
  return img;
}

// ---- PNG --------------------------------------------------------------------------------

BracketImage ReadPng(const std::string& path, const std::string& bytes) {
  Raster r;
  try {
    r = DecodePng(bytes, path);
  } catch (const Error& e) {
    throw Error(path + ": cannot read image (" + e.what() + ")");
  }
  BracketImage img = Sized(r.width, r.height, r.bits);
  const bool grey = r.channels < 3;
  for (int y = 0; y < r.height; ++y) {
    for (int x = 0; x < r.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int k = x * r.channels + (grey ? 0 : c);
        img.rgb[img.index(x, y) + c] = r.bits == 16 ? r.row16(y)[k] : r.row(y)[k];
      }
    }
  }
  return img;
}

}  // namespace
}  // namespace skycal::capture

// ---- TIFF -------------------------------------------------------------------------------
namespace skycal::capture {
namespace {

// libtiff reports through process-wide handlers: the last error of this thread is kept for
// the message, warnings (unknown tags, ...) are dropped.
thread_local std::string tiff_error;
void OnTiffError(const char* module, const char* fmt, va_list ap) {
  char buf[512];
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  tiff_error = (module ? std::string(module) + ": " : std::string()) + buf;
}
void InstallTiffHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(OnTiffError);
    TIFFSetWarningHandler(nullptr);
  });
}

// Strip-organised, interleaved grey or RGB(A) of 8 or 16 bits: scanline by scanline, the
// codes as stored. False when the file is laid out otherwise.
bool ReadTiffScanlines(TIFF* tif, BracketImage* img) {
  uint16_t bits = 0, spp = 0, planar = PLANARCONFIG_CONTIG, photometric = 0;
  uint32_t w = 0, h = 0;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
  const std::string size = RefusedImageSize(w, h);
  if (!size.empty()) throw Error(size);
  const bool grey = photometric == PHOTOMETRIC_MINISBLACK && (spp == 1 || spp == 2);
  const bool rgb = photometric == PHOTOMETRIC_RGB && (spp == 3 || spp == 4);
  if (TIFFIsTiled(tif) || planar != PLANARCONFIG_CONTIG || (bits != 8 && bits != 16) || !(grey || rgb)) return false;
  *img = Sized(static_cast<int>(w), static_cast<int>(h), bits);
  std::vector<uint8_t> line(TIFFScanlineSize(tif));
  for (uint32_t y = 0; y < h; ++y) {
    if (TIFFReadScanline(tif, line.data(), y) < 0) throw Error("a strip does not decode (" + tiff_error + ")");
    const auto* l16 = reinterpret_cast<const uint16_t*>(line.data());
    for (uint32_t x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t k = static_cast<size_t>(x) * spp + (grey ? 0 : c);
        img->rgb[img->index(static_cast<int>(x), static_cast<int>(y)) + c] = bits == 16 ? l16[k] : line[k];
      }
  }
  return true;
}

// Any other TIFF libtiff can render (YCbCr, palette, tiles, planar, 1-bit ...): its 8-bit
// RGBA rendering, top row first.
void ReadTiffRgba(TIFF* tif, BracketImage* img) {
  uint32_t w = 0, h = 0;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
  const std::string size = RefusedImageSize(w, h);
  if (!size.empty()) throw Error(size);
  std::vector<uint32_t> rgba(static_cast<size_t>(w) * h);
  if (!TIFFReadRGBAImageOriented(tif, w, h, rgba.data(), ORIENTATION_TOPLEFT, 0)) {
    throw Error("libtiff cannot render it (" + tiff_error + ")");
  }
  *img = Sized(static_cast<int>(w), static_cast<int>(h), 8);
  for (size_t i = 0; i < rgba.size(); ++i) {
    img->rgb[3 * i] = TIFFGetR(rgba[i]);
    img->rgb[3 * i + 1] = TIFFGetG(rgba[i]);
    img->rgb[3 * i + 2] = TIFFGetB(rgba[i]);
  }
}

BracketImage ReadTiff(const std::string& path) {
  InstallTiffHandlers();
  tiff_error.clear();
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw Error(path + ": cannot read image (TIFF: " + tiff_error + ")");
  // Floating point and the LogLuv encodings (what OpenCV writes a float image as) hold HDR
  // values, not a camera's codes.
  uint16_t format = SAMPLEFORMAT_UINT, photometric = 0;
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
  if (format == SAMPLEFORMAT_IEEEFP || photometric == PHOTOMETRIC_LOGLUV || photometric == PHOTOMETRIC_LOGL) {
    TIFFClose(tif);
    throw Error(path + ": expected an 8- or 16-bit camera image, got floating-point or LogLuv samples (float images "
                "are already HDR)");
  }
  BracketImage img;
  try {
    if (!ReadTiffScanlines(tif, &img)) ReadTiffRgba(tif, &img);
  } catch (const Error& e) {
    TIFFClose(tif);
    throw Error(path + ": cannot read image (TIFF: " + e.what() + ")");
  }
  TIFFClose(tif);
  return img;
}

// ---- orientation ------------------------------------------------------------------------

// Exif.Image.Orientation (1-8; 1 when absent or unreadable: the pixels as stored).
int ExifOrientation(const std::string& path) {
  try {
    auto image = OpenExif(path);
    const double v = ExifNumber(image->exifData(), "Exif.Image.Orientation");
    return std::isfinite(v) && v >= 1 && v <= 8 ? static_cast<int>(v) : 1;
  } catch (const std::exception&) {
    return 1;
  }
}

// The image as it is meant to be seen: EXIF orientation o (TIFF 6.0's numbering: where the
// stored rows and columns go) undone. 5-8 swap width and height.
BracketImage Oriented(BracketImage in, int o) {
  if (o <= 1) return in;  // the common case: no copy
  const bool swap = o >= 5;
  BracketImage out = Sized(swap ? in.height : in.width, swap ? in.width : in.height, in.bits);
  const int W = in.width, H = in.height;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      int sx = x, sy = y;  // the stored pixel shown at (x, y)
      switch (o) {
        case 2: sx = W - 1 - x; break;                         // mirrored left-right
        case 3: sx = W - 1 - x; sy = H - 1 - y; break;         // rotated 180
        case 4: sy = H - 1 - y; break;                         // mirrored top-bottom
        case 5: sx = y; sy = x; break;                         // transposed
        case 6: sx = y; sy = H - 1 - x; break;                 // rotated 90 clockwise to view
        case 7: sx = W - 1 - y; sy = H - 1 - x; break;         // transversed
        case 8: sx = W - 1 - y; sy = x; break;                 // rotated 90 counter-clockwise
      }
      for (int c = 0; c < 3; ++c) out.rgb[out.index(x, y) + c] = in.rgb[in.index(sx, sy) + c];
    }
  return out;
}

}  // namespace

BracketImage DecodeCameraImage(const std::string& path) {
  // The signature decides; a TIFF (16-bit developer output runs to 100 MB) is read by
  // libtiff from the file, JPEG and PNG from memory.
  const std::string head = ReadBytes(path, 8);
  auto starts = [&](const char* magic, size_t n) { return head.size() >= n && std::memcmp(head.data(), magic, n) == 0; };
  BracketImage img;
  if (starts("\xFF\xD8\xFF", 3)) {
    img = ReadJpeg(path, ReadBytes(path));
  } else if (starts("\x89PNG\r\n\x1a\n", 8)) {
    img = ReadPng(path, ReadBytes(path));
  } else if (starts("II*\0", 4) || starts("MM\0*", 4)) {
    img = ReadTiff(path);
  } else {
    throw Error(path + ": cannot read image (not a JPEG, PNG or TIFF file; camera RAW files are recognised by their "
                "extension, and float images are already HDR)");
  }
  if (img.empty()) throw Error(path + ": cannot read image (it has no pixels)");
  return Oriented(std::move(img), ExifOrientation(path));
}

}  // namespace skycal::capture
