#pragma once
// What the plan figures and the line charts draw with: one sub-pixel canvas (OpenCV's
// fixed-point anti-aliased primitives), one font, the text and frame inks.
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

// A region of an image that clips everything drawn into it; takes whole-image coordinates.
// `pixel_centre`: where pixel 0's centre is, 0.0 (line charts: centres at integers) or 0.5 (plan
// figures: pixel i covers [i, i+1)).
class Canvas {
 public:
  Canvas(cv::Mat& image, const cv::Rect& rect, double pixel_centre)
      : img_(image(rect)), tl_(rect.tl()), centre_(pixel_centre) {}

  // The fixed-point image point of p, relative to the region.
  cv::Point fixed(const cv::Point2d& p) const {
    return cv::Point(cvRound((p.x - tl_.x - centre_) * kOne), cvRound((p.y - tl_.y - centre_) * kOne));
  }
  void line(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness = 1);
  void disc(const cv::Point2d& c, double r, const cv::Scalar& colour);
  void ring(const cv::Point2d& c, double r, const cv::Scalar& colour, int thickness = 1);
  void cross(const cv::Point2d& c, double r, const cv::Scalar& colour);
  void rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness = 1);
  // Ellipse with semi-axes (a, b) px, the a-axis at angle_deg (image frame, clockwise).
  void ellipse(const cv::Point2d& c, double a, double b, double angle_deg, const cv::Scalar& colour, int thickness);
  void polygon(const std::vector<cv::Point2d>& pts, const cv::Scalar& colour);
  // Text with its baseline starting at p; align: 0 left, 1 centre, 2 right.
  void text(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, int thickness = 1,
            int align = 0);
  // Text centred on p both ways.
  void text_centred(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                    int thickness = 1);
  // Text centred on p on a filled box.
  void label(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, const cv::Scalar& box);
  cv::Mat& mat() { return img_; }

 private:
  cv::Mat img_;
  cv::Point tl_;
  double centre_;
};

}  // namespace pbnbv::drawing
