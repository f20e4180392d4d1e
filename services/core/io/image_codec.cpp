#include "core/io/image_codec.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

// After <cstdio>: jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>
#include <png.h>

// libpng and libjpeg report an error by calling back, and the callback must not return: it
// long-jumps back to the setjmp of the function that called them. No C++ object with a destructor
// lives in such a function's frame; what the callbacks and the caller share sits in a context
// struct reached through a pointer, and the caller turns a failure into an exception after the
// library's structures are destroyed.

namespace pbnbv {
namespace {

bool little_endian_host() {
  const uint16_t probe = 1;
  uint8_t first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// ---- PNG ----

struct PngContext {
  char message[256] = "";
  bool from_library = false;  // the message is libpng's (the data is broken), not one of our checks
  const uint8_t* in = nullptr;  // decoding: the bytes, their size, how far libpng has read
  std::size_t in_size = 0;
  std::size_t in_at = 0;
  std::vector<uint8_t>* out = nullptr;  // encoding: where the bytes go
};

[[noreturn]] void png_fail(png_structp png, png_const_charp message) {
  auto* c = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(c->message, sizeof c->message, "%s", message);
  c->from_library = true;
  png_longjmp(png, 1);
}

void png_warn(png_structp, png_const_charp) {}  // an unknown or damaged ancillary chunk: not the image

void png_put(png_structp png, png_bytep data, png_size_t n) {
  auto* c = static_cast<PngContext*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    c->out->insert(c->out->end(), data, data + n);
  } catch (...) {
    ok = false;
  }
  if (!ok) png_error(png, "out of memory for the encoded image");
}

void png_flush_nothing(png_structp) {}

void png_take(png_structp png, png_bytep data, png_size_t n) {
  auto* c = static_cast<PngContext*>(png_get_io_ptr(png));
  if (n > c->in_size - c->in_at) png_error(png, "the PNG ends early (truncated)");
  std::memcpy(data, c->in + c->in_at, n);
  c->in_at += n;
}

bool png_encode(PngContext* c, const uint8_t* pixels, int width, int height, int bit_depth, int colour_type,
                bool bgr, std::size_t stride, int compression, bool swap) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, c, png_fail, png_warn);
  if (png == nullptr) {
    std::snprintf(c->message, sizeof c->message, "libpng could not start an encoder");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    std::snprintf(c->message, sizeof c->message, "libpng could not start an encoder");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, c, png_put, png_flush_nothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth, colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, compression);
  png_write_info(png, info);
  if (swap) png_set_swap(png);  // host-order 16-bit samples; PNG stores them big-endian
  if (bgr) png_set_bgr(png);
  for (int v = 0; v < height; ++v) png_write_row(png, pixels + static_cast<std::size_t>(v) * stride);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

bool png_decode_gray16(PngContext* c, int64_t max_pixels, bool swap, Gray16Image* image) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, c, png_fail, png_warn);
  if (png == nullptr) {
    std::snprintf(c->message, sizeof c->message, "libpng could not start a decoder");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    std::snprintf(c->message, sizeof c->message, "libpng could not start a decoder");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, c, png_take);
  png_read_info(png, info);
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int depth = 0;
  int type = 0;
  png_get_IHDR(png, info, &width, &height, &depth, &type, nullptr, nullptr, nullptr);
  if (depth != 16 || type != PNG_COLOR_TYPE_GRAY) {
    const char* kind = type == PNG_COLOR_TYPE_GRAY         ? "grey"
                       : type == PNG_COLOR_TYPE_GRAY_ALPHA ? "grey and alpha"
                       : type == PNG_COLOR_TYPE_PALETTE    ? "palette"
                       : type == PNG_COLOR_TYPE_RGB        ? "colour"
                                                           : "colour and alpha";
    std::snprintf(c->message, sizeof c->message, "holds %d-bit %s samples, not 16-bit grey (one channel)", depth, kind);
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  const int64_t pixels = static_cast<int64_t>(width) * static_cast<int64_t>(height);
  if (pixels > max_pixels) {
    std::snprintf(c->message, sizeof c->message, "declares %u x %u pixels, more than the %lld allowed", width, height,
                  static_cast<long long>(max_pixels));
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  if (swap) png_set_swap(png);
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  bool allocated = true;
  try {
    image->width = static_cast<int>(width);
    image->height = static_cast<int>(height);
    image->samples.assign(static_cast<std::size_t>(pixels), 0);
  } catch (...) {
    allocated = false;
  }
  if (!allocated) {
    std::snprintf(c->message, sizeof c->message, "out of memory for the decoded image");
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  for (int pass = 0; pass < passes; ++pass) {
    for (png_uint_32 v = 0; v < height; ++v) {
      png_read_row(png, reinterpret_cast<png_bytep>(image->samples.data() + static_cast<std::size_t>(v) * width),
                   nullptr);
    }
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

// ---- JPEG ----

struct JpegContext {
  jpeg_error_mgr manager;  // first: libjpeg hands the callbacks a pointer to it
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
  bool from_library = false;  // the message is libjpeg's (an error or a warning on the data), not one of our checks
  int warnings = 0;
  unsigned char* buffer = nullptr;  // encoding: jpeg_mem_dest's buffer (malloc'ed by libjpeg)
  unsigned long length = 0;
};

[[noreturn]] void jpeg_fail(j_common_ptr cinfo) {
  auto* c = reinterpret_cast<JpegContext*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, c->message);
  c->from_library = true;
  std::longjmp(c->jump, 1);
}

// A warning while decoding is damaged data (a premature end, bytes before a marker, a bad
// Huffman code): libjpeg goes on and makes up the rest of the image, which here is an error.
void jpeg_note(j_common_ptr cinfo, int level) {
  if (level >= 0) return;  // trace messages
  auto* c = reinterpret_cast<JpegContext*>(cinfo->err);
  if (c->warnings++ == 0) {
    (*cinfo->err->format_message)(cinfo, c->message);
    c->from_library = true;
  }
}

bool jpeg_encode(JpegContext* c, const uint8_t* rgb, int width, int height, int quality) {
  jpeg_compress_struct cinfo;
  cinfo.err = jpeg_std_error(&c->manager);
  c->manager.error_exit = jpeg_fail;
  if (setjmp(c->jump)) {
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, &c->buffer, &c->length);
  cinfo.image_width = static_cast<JDIMENSION>(width);
  cinfo.image_height = static_cast<JDIMENSION>(height);
  cinfo.input_components = 3;
  cinfo.in_color_space = JCS_RGB;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(rgb + cinfo.next_scanline * stride);
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

bool jpeg_decode(JpegContext* c, const uint8_t* bytes, std::size_t size, int64_t max_pixels, Rgb8Image* image) {
  jpeg_decompress_struct cinfo;
  cinfo.err = jpeg_std_error(&c->manager);
  c->manager.error_exit = jpeg_fail;
  c->manager.emit_message = jpeg_note;
  if (setjmp(c->jump)) {
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  const int64_t pixels = static_cast<int64_t>(cinfo.image_width) * static_cast<int64_t>(cinfo.image_height);
  if (pixels > max_pixels) {
    std::snprintf(c->message, sizeof c->message, "declares %u x %u pixels, more than the %lld allowed",
                  cinfo.image_width, cinfo.image_height, static_cast<long long>(max_pixels));
    c->from_library = false;  // ours, even after a warning on the header
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&cinfo);
  bool allocated = true;
  try {
    image->width = static_cast<int>(cinfo.output_width);
    image->height = static_cast<int>(cinfo.output_height);
    image->rgb.assign(static_cast<std::size_t>(pixels) * 3, 0);
  } catch (...) {
    allocated = false;
  }
  if (!allocated || cinfo.output_components != 3) {
    std::snprintf(c->message, sizeof c->message, "%s",
                  allocated ? "does not decode to three channels" : "out of memory for the decoded image");
    c->from_library = false;
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  const std::size_t stride = static_cast<std::size_t>(cinfo.output_width) * 3;
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = image->rgb.data() + cinfo.output_scanline * stride;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return c->warnings == 0;
}

void check_size(int width, int height, const std::string& what, const char* ctx) {
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535) {
    throw std::invalid_argument(std::string(ctx) + ": " + what + ": " + std::to_string(width) + " x " +
                                std::to_string(height) + " is not an image size (1..65535 a side)");
  }
}

}  // namespace

std::vector<uint8_t> encode_png(const void* pixels, int width, int height, PngPixels format, int compression,
                                const std::string& what) {
  check_size(width, height, what, "encode_png");
  if (compression < 0 || compression > 9) {
    throw std::invalid_argument("encode_png: " + what + ": compression " + std::to_string(compression) +
                                " is not a zlib level (0..9)");
  }
  if (pixels == nullptr) throw std::invalid_argument("encode_png: " + what + ": no pixels");
  const bool sixteen = format == PngPixels::kGray16;
  const bool grey = format == PngPixels::kGray8 || sixteen;
  const std::size_t stride = static_cast<std::size_t>(width) * (grey ? 1 : 3) * (sixteen ? 2 : 1);
  std::vector<uint8_t> out;
  PngContext c;
  c.out = &out;
  if (!png_encode(&c, static_cast<const uint8_t*>(pixels), width, height, sixteen ? 16 : 8,
                  grey ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, format == PngPixels::kBgr8, stride, compression,
                  sixteen && little_endian_host())) {
    throw std::runtime_error("encode_png: " + what + ": libpng: " + c.message);
  }
  return out;
}

Gray16Image decode_png_gray16(const uint8_t* bytes, std::size_t size, const std::string& what, int64_t max_pixels) {
  if (bytes == nullptr || size < 8 || png_sig_cmp(bytes, 0, 8) != 0) {
    throw std::runtime_error(what + ": not a PNG (" + std::to_string(size) +
                             " bytes that do not begin with the PNG signature)");
  }
  PngContext c;
  c.in = bytes;
  c.in_size = size;
  Gray16Image image;
  if (!png_decode_gray16(&c, max_pixels, little_endian_host(), &image)) {
    throw std::runtime_error(what + ": " + (c.from_library ? "a broken PNG (libpng: " + std::string(c.message) + ")"
                                                           : std::string(c.message)));
  }
  return image;
}

std::vector<uint8_t> encode_jpeg(const uint8_t* rgb, int width, int height, int quality, const std::string& what) {
  check_size(width, height, what, "encode_jpeg");
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("encode_jpeg: " + what + ": quality " + std::to_string(quality) + " is not in 1..100");
  }
  if (rgb == nullptr) throw std::invalid_argument("encode_jpeg: " + what + ": no pixels");
  JpegContext c;
  const bool ok = jpeg_encode(&c, rgb, width, height, quality);
  std::vector<uint8_t> out;
  if (ok) {
    try {
      out.assign(c.buffer, c.buffer + c.length);
    } catch (...) {
      std::free(c.buffer);
      throw;
    }
  }
  std::free(c.buffer);
  if (!ok) throw std::runtime_error("encode_jpeg: " + what + ": libjpeg: " + c.message);
  return out;
}

Rgb8Image decode_jpeg_rgb(const uint8_t* bytes, std::size_t size, const std::string& what, int64_t max_pixels) {
  if (bytes == nullptr || size < 2 || bytes[0] != 0xFF || bytes[1] != 0xD8) {
    throw std::runtime_error(what + ": not a JPEG (" + std::to_string(size) +
                             " bytes that do not begin with a start-of-image marker)");
  }
  JpegContext c;
  Rgb8Image image;
  if (!jpeg_decode(&c, bytes, size, max_pixels, &image)) {
    throw std::runtime_error(what + ": " + (c.from_library ? "a broken JPEG (libjpeg: " + std::string(c.message) + ")"
                                                           : std::string(c.message)));
  }
  return image;
}

}  // namespace pbnbv
