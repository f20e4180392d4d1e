#pragma once
// What the plan figures and the line charts draw with: one sub-pixel canvas (OpenCV's
// fixed-point anti-aliased primitives), one font, the text and frame inks. A canvas draws into
// an image and, when given one, records the same primitives as SVG elements: one drawing code,
// two back ends (PNG from the image, SVG from the record).
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <string>
#include <vector>

namespace pbnbv::drawing {

inline constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
// Sub-pixel precision: coordinates go to OpenCV's fixed point with kShift fractional bits.
inline constexpr int kShift = 4;
inline constexpr double kOne = 1 << kShift;

// Inks shared by every figure (BGR).
inline const cv::Scalar kBlack(0, 0, 0);
inline const cv::Scalar kText(40, 40, 40);
inline const cv::Scalar kSubText(90, 90, 90);
inline const cv::Scalar kFrame(150, 150, 150);

inline cv::Scalar scalar(const cv::Vec3b& c) { return cv::Scalar(c[0], c[1], c[2]); }

// Size of `s` in the figures' font; `baseline` (optional) receives the descent below it.
cv::Size text_size(const std::string& s, double scale, int thickness, int* baseline = nullptr);

// An SVG document of width x height user units (one unit = one image pixel; pixel i covers
// [i, i+1)), built element by element in drawing order.
class Svg {
 public:
  Svg(int width, int height);
  // Registers a clip rectangle (image pixels) and returns its id ("" for the whole image).
  std::string clip(const cv::Rect& r);
  // Appends one element; `clip_id` from clip() or "".
  void add(const std::string& element, const std::string& clip_id);
  std::string document() const;
  int width() const { return w_; }
  int height() const { return h_; }

 private:
  int w_, h_;
  std::vector<std::string> defs_, body_;
  std::vector<cv::Rect> clips_;
};

// "#rrggbb" of a BGR colour.
std::string svg_colour(const cv::Scalar& bgr);
// `s` with &, <, >, " escaped for XML.
std::string xml_escape(const std::string& s);

// Writes `text` to `path` atomically (path + ".tmp", then renamed). Throws std::runtime_error
// naming `what` and the path when it cannot be written.
void write_text_file(const std::string& path, const std::string& text, const std::string& what);

// The SVG file beside a PNG: the same path with its extension replaced by ".svg".
std::string svg_path_beside(const std::string& png_path);

// A region of an image that clips everything drawn into it; takes whole-image coordinates.
// `pixel_centre`: where pixel 0's centre is, 0.0 (line charts: centres at integers) or 0.5 (plan
// figures: pixel i covers [i, i+1)). With `svg`, every primitive is also recorded there, clipped
// to the same region.
class Canvas {
 public:
  Canvas(cv::Mat& image, const cv::Rect& rect, double pixel_centre, Svg* svg = nullptr);

  // The fixed-point image point of p, relative to the region.
  cv::Point fixed(const cv::Point2d& p) const {
    return cv::Point(cvRound((p.x - tl_.x - centre_) * kOne), cvRound((p.y - tl_.y - centre_) * kOne));
  }
  void line(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness = 1);
  void disc(const cv::Point2d& c, double r, const cv::Scalar& colour);
  void ring(const cv::Point2d& c, double r, const cv::Scalar& colour, int thickness = 1);
  void cross(const cv::Point2d& c, double r, const cv::Scalar& colour);
  void rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness = 1);
  // Ellipse with semi-axes (a, b) px, the a-axis at angle_deg (image frame, clockwise);
  // thickness cv::FILLED fills it, with opacity `alpha` (1: opaque).
  void ellipse(const cv::Point2d& c, double a, double b, double angle_deg, const cv::Scalar& colour, int thickness,
               double alpha = 1.0);
  void polygon(const std::vector<cv::Point2d>& pts, const cv::Scalar& colour, double alpha = 1.0);
  // Whole pixels (no anti-aliasing), in whole-image pixel indices: a 1-px line from pixel a to
  // pixel b, a filled rectangle.
  void pixel_line(const cv::Point& a, const cv::Point& b, const cv::Scalar& colour);
  void fill_rect(const cv::Rect& r, const cv::Scalar& colour);
  // Text with its baseline starting at p; align: 0 left, 1 centre, 2 right.
  void text(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, int thickness = 1,
            int align = 0);
  // Text centred on p both ways.
  void text_centred(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                    int thickness = 1);
  // Text turned 90 degrees counter-clockwise (reading upwards), centred on pixel `centre` (on a
  // white background: drawn by taking the darker of text and image).
  void text_up(const std::string& s, const cv::Point& centre, double scale, const cv::Scalar& colour,
               int thickness = 1);
  // Text centred on p on a filled box.
  void label(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, const cv::Scalar& box);
  cv::Mat& mat() { return img_; }

 private:
  // Whole-image SVG coordinate of a canvas point (pixel i's centre is at i + 0.5 in SVG).
  double sx(double x) const { return x - centre_ + 0.5; }
  double sy(double y) const { return y - centre_ + 0.5; }
  void svg_text(const std::string& s, double left, double baseline, double scale, const cv::Scalar& colour,
                int thickness, const std::string& transform = "");
  cv::Mat img_;
  cv::Point tl_;
  double centre_;
  Svg* svg_;
  std::string clip_;
};

}  // namespace pbnbv::drawing
