// libpng's classic API (its simplified API treats 16-bit data as linear light and converts
// it; skycal's 16-bit PNGs are raw camera codes and flow codes, to be kept as they are).
// libpng reports errors by longjmp: each setjmp frame below holds only plain pointers, the
// C++ objects live in the caller.
#include "skycal/core/png_io.h"

#include <png.h>

#include <bit>
#include <cstring>
#include <string>

#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"

namespace skycal {

Raster::Raster(int w, int h, int c, int b)
    : width(w), height(h), channels(c), bits(b), data(static_cast<size_t>(w) * h * c * (b / 8)) {}

std::string RefusedImageSize(long long width, long long height) {
  if (width <= 0 || height <= 0) return "it has no pixels";
  if (width > kMaxExrSide || height > kMaxExrSide || width * height > kMaxExrPixels) {
    return "its header claims " + std::to_string(width) + " x " + std::to_string(height) + " pixels, more than skycal reads (" +
           std::to_string(kMaxExrSide) + " a side, " + std::to_string(kMaxExrPixels) + " in all)";
  }
  return {};
}

namespace {

struct Context {
  std::string message;                  // libpng's error text
  std::vector<uint8_t>* out = nullptr;  // encoding: the bytes so far
  const std::string* in = nullptr;      // decoding: the file's bytes
  size_t read_at = 0;
};

void OnError(png_structp png, png_const_charp msg) {
  static_cast<Context*>(png_get_error_ptr(png))->message = msg;
  png_longjmp(png, 1);
}
void OnWarning(png_structp, png_const_charp) {}
void OnWrite(png_structp png, png_bytep data, png_size_t n) {
  auto* c = static_cast<Context*>(png_get_io_ptr(png));
  c->out->insert(c->out->end(), data, data + n);
}
void OnFlush(png_structp) {}
void OnRead(png_structp png, png_bytep data, png_size_t n) {
  auto* c = static_cast<Context*>(png_get_io_ptr(png));
  if (c->read_at + n > c->in->size()) png_error(png, "unexpected end of file (truncated)");
  std::memcpy(data, c->in->data() + c->read_at, n);
  c->read_at += n;
}

int ColorType(int channels) {
  switch (channels) {
    case 1: return PNG_COLOR_TYPE_GRAY;
    case 2: return PNG_COLOR_TYPE_GRAY_ALPHA;
    case 3: return PNG_COLOR_TYPE_RGB;
    default: return PNG_COLOR_TYPE_RGB_ALPHA;
  }
}

// The write between png_create_write_struct and png_write_end: false on a libpng error.
bool Write(png_structp png, png_infop info, const Raster& image, int compression, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, image.width, image.height, image.bits, ColorType(image.channels), PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, compression);
  png_write_info(png, info);
  if (image.bits == 16 && std::endian::native == std::endian::little) png_set_swap(png);  // PNG is big-endian
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

}  // namespace

std::vector<uint8_t> EncodePng(const Raster& image, const std::string& what, int compression) {
  if (image.width <= 0 || image.height <= 0 || image.channels < 1 || image.channels > 4 ||
      (image.bits != 8 && image.bits != 16) || image.data.size() != image.row_bytes() * image.height) {
    throw Error(what + ": cannot encode a " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", " +
                std::to_string(image.channels) + "-channel, " + std::to_string(image.bits) +
                "-bit raster as PNG (expected 1-4 channels of 8 or 16 bits, rows packed)");
  }
  std::vector<uint8_t> bytes;
  Context ctx;
  ctx.out = &bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, OnError, OnWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw Error(what + ": PNG encoding failed (libpng could not start)");
  }
  png_set_write_fn(png, &ctx, OnWrite, OnFlush);
  std::vector<png_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y) rows[y] = const_cast<png_bytep>(image.row(y));
  const bool ok = Write(png, info, image, compression, rows.data());
  png_destroy_write_struct(&png, &info);
  if (!ok) throw Error(what + ": PNG encoding failed (libpng: " + ctx.message + ")");
  return bytes;
}

namespace {

// The read after png_create_read_struct: the raster, or false on a libpng error. `image` is
// sized here (before any row is read: a longjmp from a row leaves it whole).
bool Read(png_structp png, png_infop info, Raster* image, std::vector<png_bytep>* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  const int color = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const long long w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  static_cast<Context*>(png_get_error_ptr(png))->message = RefusedImageSize(w, h);
  if (!static_cast<Context*>(png_get_error_ptr(png))->message.empty()) return false;
  const int width = static_cast<int>(w), height = static_cast<int>(h);
  *image = Raster(width, height, png_get_channels(png, info), png_get_bit_depth(png, info) == 16 ? 16 : 8);
  rows->resize(height);
  for (int y = 0; y < height; ++y) (*rows)[y] = image->row(y);
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  return true;
}

}  // namespace

Raster DecodePng(const std::string& bytes, const std::string& what) {
  if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0) {
    throw Error(what + ": not a PNG file (its first 8 bytes are not the PNG signature)");
  }
  Context ctx;
  ctx.in = &bytes;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, OnError, OnWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw Error(what + ": PNG decoding failed (libpng could not start)");
  }
  png_set_read_fn(png, &ctx, OnRead);
  Raster image;
  std::vector<png_bytep> rows;
  const bool ok = Read(png, info, &image, &rows);
  png_destroy_read_struct(&png, &info, nullptr);
  if (!ok) throw Error(what + ": the PNG does not decode (libpng: " + ctx.message + ")");
  return image;
}

}  // namespace skycal
