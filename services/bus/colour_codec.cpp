#include "bus/colour_codec.hpp"

#include <stdexcept>

#include "bus/message_guard.hpp"
#include "core/io/image_codec.hpp"

namespace pbnbv::bus {

std::vector<uint8_t> encode_jpeg(const std::vector<uint8_t>& rgb, int width, int height, int quality) {
  if (width <= 0 || height <= 0 || rgb.size() != static_cast<std::size_t>(width) * height * 3) {
    throw std::invalid_argument("encode_jpeg: " + std::to_string(rgb.size()) + " bytes are not a " +
                                std::to_string(width) + " x " + std::to_string(height) + " R G B image");
  }
  return pbnbv::encode_jpeg(rgb.data(), width, height, quality, "colour image");
}

std::optional<std::pair<int, int>> jpeg_size(const std::vector<uint8_t>& b) {
  if (b.size() < 4 || b[0] != 0xFF || b[1] != 0xD8) return std::nullopt;  // SOI
  std::size_t at = 2;
  while (at + 4 <= b.size()) {
    if (b[at] != 0xFF) return std::nullopt;
    const uint8_t marker = b[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    const std::size_t length = (static_cast<std::size_t>(b[at + 2]) << 8) | b[at + 3];
    if (length < 2) return std::nullopt;
    // SOF0..SOF15 but DHT (C4), JPG (C8) and DAC (CC): precision, height, width.
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (at + 9 > b.size()) return std::nullopt;
      const int height = (b[at + 5] << 8) | b[at + 6];
      const int width = (b[at + 7] << 8) | b[at + 8];
      return std::make_pair(width, height);
    }
    if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan or end before a frame header
    at += 2 + length;
  }
  return std::nullopt;
}

std::optional<ColourImage> colour_camera(const depth_frame_t& f) {
  if (f.colour_encoding == depth_frame_t::kColourNone) return std::nullopt;
  const std::string what = "DEPTH_FRAME " + std::to_string(f.seq) + " colour";
  ColourImage c;
  c.intrinsics = CameraIntrinsics{f.colour_width, f.colour_height, f.colour_fx, f.colour_fy, f.colour_cx, f.colour_cy};
  c.distortion = LensDistortion::from({f.colour_distortion[0], f.colour_distortion[1], f.colour_distortion[2],
                                       f.colour_distortion[3], f.colour_distortion[4]});
  c.depth_T_colour = pose_from_arrays(f.depth_T_colour.position_m, f.depth_T_colour.quat_wxyz, what + " depth_T_colour");
  c.validate_camera(what);
  if (static_cast<int64_t>(f.colour_width) * f.colour_height > kMaxFramePixels) {
    throw std::invalid_argument(what + " image " + std::to_string(f.colour_width) + " x " +
                                std::to_string(f.colour_height) + " exceeds the contract's " +
                                std::to_string(kMaxFramePixels) + " pixels");
  }
  const std::size_t want = static_cast<std::size_t>(f.colour_width) * f.colour_height * 3;
  if (f.colour_encoding == depth_frame_t::kColourRgb8) {
    if (f.colour.size() != want) {
      throw std::invalid_argument(what + ": " + std::to_string(f.colour.size()) + " bytes (rgb8) for a " +
                                  std::to_string(f.colour_width) + " x " + std::to_string(f.colour_height) +
                                  " image (" + std::to_string(want) + " wanted)");
    }
  } else if (f.colour_encoding == depth_frame_t::kColourJpeg) {
    const std::optional<std::pair<int, int>> size = jpeg_size(f.colour);
    if (!size) throw std::invalid_argument(what + " (jpeg): the bytes are not a JPEG with a frame header");
    if (size->first != f.colour_width || size->second != f.colour_height) {
      throw std::invalid_argument(what + " (jpeg) is " + std::to_string(size->first) + " x " +
                                  std::to_string(size->second) + ", the frame says " + std::to_string(f.colour_width) +
                                  " x " + std::to_string(f.colour_height));
    }
  } else {
    throw std::invalid_argument(what + "_encoding = " + std::to_string(f.colour_encoding) +
                                " is not one of its constants (0 none, 1 rgb8, 2 jpeg)");
  }
  return c;
}

std::optional<ColourImage> decode_colour(const depth_frame_t& f) {
  std::optional<ColourImage> c = colour_camera(f);
  if (!c) return c;
  const std::string what = "DEPTH_FRAME " + std::to_string(f.seq) + " colour";
  const std::size_t want = static_cast<std::size_t>(f.colour_width) * f.colour_height * 3;
  if (f.colour_encoding == depth_frame_t::kColourRgb8) {
    c->rgb = f.colour;
  } else {
    Rgb8Image image;
    try {
      image = decode_jpeg_rgb(f.colour.data(), f.colour.size(), what + " (jpeg)", kMaxFramePixels);
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());
    }
    if (image.width != f.colour_width || image.height != f.colour_height || image.rgb.size() != want) {
      throw std::invalid_argument(what + " (jpeg) decodes to " + std::to_string(image.width) + " x " +
                                  std::to_string(image.height) + ", the frame says " + std::to_string(f.colour_width) +
                                  " x " + std::to_string(f.colour_height));
    }
    c->rgb = std::move(image.rgb);
  }
  return c;  // its camera checked by colour_camera, its size by the checks above
}

void set_colour(depth_frame_t& f, const ColourImage& image, int64_t utime, int8_t encoding, int jpeg_quality) {
  image.validate("colour image");
  const CameraIntrinsics& k = image.intrinsics;
  f.colour_width = k.width;
  f.colour_height = k.height;
  f.colour_fx = k.fx;
  f.colour_fy = k.fy;
  f.colour_cx = k.cx;
  f.colour_cy = k.cy;
  const std::array<double, 5> d = image.distortion.coefficients();
  for (int i = 0; i < 5; ++i) f.colour_distortion[i] = d[static_cast<std::size_t>(i)];
  pose_to_arrays(image.depth_T_colour, f.depth_T_colour.position_m, f.depth_T_colour.quat_wxyz);
  f.colour_utime = utime;
  if (encoding == depth_frame_t::kColourJpeg) {
    f.colour = encode_jpeg(image.rgb, k.width, k.height, jpeg_quality);
  } else if (encoding == depth_frame_t::kColourRgb8) {
    f.colour = image.rgb;
  } else {
    throw std::invalid_argument("set_colour: encoding " + std::to_string(encoding) + " is neither rgb8 nor jpeg");
  }
  f.colour_encoding = encoding;
  f.colour_num_bytes = static_cast<int32_t>(f.colour.size());
}

}  // namespace pbnbv::bus
