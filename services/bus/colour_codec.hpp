#pragma once
// A frame's colour image on DEPTH_FRAME (depth_frame_t colour_*): R G B bytes, raw or as JPEG
// (libjpeg, core/io/image_codec.hpp). A JPEG from the wire is sized from its own header before anything is
// decoded, and refused unless that is the size the frame declares.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/colour_image.hpp"
#include "pbnbv/depth_frame_t.hpp"

namespace pbnbv::bus {

// `rgb` (width x height x 3, R G B, row 0 at the top) as a baseline JPEG at `quality` (1..100).
std::vector<uint8_t> encode_jpeg(const std::vector<uint8_t>& rgb, int width, int height, int quality = 90);

// The width and height a JPEG's frame header (its first SOFn marker) states; nullopt when the
// bytes are not a JPEG or end before one.
std::optional<std::pair<int, int>> jpeg_size(const std::vector<uint8_t>& jpeg);

// The camera of the colour image a frame carries, its pixels not decoded (rgb empty; nullopt:
// colour_encoding kColourNone): what writing the image as it came needs. Checked as decode_colour
// checks it, but for the JPEG's decoding.
std::optional<ColourImage> colour_camera(const depth_frame_t& f);

// The colour image a frame carries (nullopt: colour_encoding kColourNone). Throws
// std::invalid_argument naming the frame and the bad field: the colour camera model, the pose,
// an unknown encoding, a size that is not the declared image's, a JPEG that does not decode.
std::optional<ColourImage> decode_colour(const depth_frame_t& f);

// Fills a frame's colour fields with `image`, its pixels as `encoding` (kColourRgb8 or kColourJpeg)
// says, exposed at `utime`. Throws std::invalid_argument when the image is not valid.
void set_colour(depth_frame_t& f, const ColourImage& image, int64_t utime, int8_t encoding, int jpeg_quality = 90);

}  // namespace pbnbv::bus
