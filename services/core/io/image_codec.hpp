#pragma once
// PNG and JPEG in memory, through libpng and libjpeg(-turbo) directly: the depth images a scan
// folder holds (16-bit grey PNG), the plan figures (colour PNG) and a frame's colour image on the
// wire (JPEG). Not through OpenCV's imgcodecs, which loads about 130 shared libraries (GDAL,
// Poppler, HDF5, ...) into every process that links it: 0.1-0.2 s of CPU at each start of each
// service, for two codecs.
//
// Nothing read is trusted: a decoder takes the caller's bound on the pixels and refuses a header
// beyond it before it allocates, and every error names `what` (a path, a frame) and says what is
// wrong with it.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pbnbv {

// The pixel layouts encode_png writes: 8-bit grey, 16-bit grey (host-order uint16_t, written
// big-endian as PNG stores it), and 8-bit colour as R G B or as B G R (OpenCV's order).
enum class PngPixels { kGray8, kGray16, kRgb8, kBgr8 };

// `pixels` (row-major, rows of width * channels samples, row 0 at the top) as a PNG at zlib level
// `compression` (0..9). Throws std::invalid_argument naming `what` when the size or level is
// not valid, std::runtime_error when libpng fails.
std::vector<uint8_t> encode_png(const void* pixels, int width, int height, PngPixels format, int compression,
                                const std::string& what);

// A 16-bit grey PNG (any interlacing) as its samples, row-major.
struct Gray16Image {
  int width = 0;
  int height = 0;
  std::vector<uint16_t> samples;
};

// Decodes `bytes` as a 16-bit single-channel PNG. Throws std::runtime_error "<what>: ..." when
// the bytes are not a PNG, the PNG is broken or truncated, is not 16-bit grey, or declares more
// than `max_pixels` pixels.
Gray16Image decode_png_gray16(const uint8_t* bytes, std::size_t size, const std::string& what, int64_t max_pixels);

// `rgb` (width * height * 3 bytes, R G B, row 0 at the top) as a baseline JPEG at `quality`
// (1..100, 4:2:0). Throws std::invalid_argument naming `what` when the size or quality is not
// valid, std::runtime_error when libjpeg fails.
std::vector<uint8_t> encode_jpeg(const uint8_t* rgb, int width, int height, int quality, const std::string& what);

// A decoded 8-bit colour image, R G B.
struct Rgb8Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;
};

// Decodes `bytes` as a JPEG into R G B. Throws std::runtime_error "<what>: ..." when the bytes
// are not a JPEG, it is broken or truncated (libjpeg's message), or it declares more than
// `max_pixels` pixels.
Rgb8Image decode_jpeg_rgb(const uint8_t* bytes, std::size_t size, const std::string& what, int64_t max_pixels);

}  // namespace pbnbv
