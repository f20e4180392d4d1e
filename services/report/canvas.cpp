#include "report/canvas.hpp"

#include <algorithm>

namespace pbnbv::drawing {

cv::Size text_size(const std::string& s, double scale, int thickness, int* baseline) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(s, kFont, scale, thickness, &base);
  if (baseline) *baseline = base;
  return sz;
}

void Canvas::line(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness) {
  cv::line(img_, fixed(a), fixed(b), colour, thickness, cv::LINE_AA, kShift);
}

void Canvas::disc(const cv::Point2d& c, double r, const cv::Scalar& colour) {
  cv::circle(img_, fixed(c), cvRound(r * kOne), colour, cv::FILLED, cv::LINE_AA, kShift);
}

void Canvas::ring(const cv::Point2d& c, double r, const cv::Scalar& colour, int thickness) {
  cv::circle(img_, fixed(c), cvRound(r * kOne), colour, thickness, cv::LINE_AA, kShift);
}

void Canvas::cross(const cv::Point2d& c, double r, const cv::Scalar& colour) {
  line(c + cv::Point2d(-r, -r), c + cv::Point2d(r, r), colour);
  line(c + cv::Point2d(-r, r), c + cv::Point2d(r, -r), colour);
}

void Canvas::rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness) {
  cv::rectangle(img_, fixed(a), fixed(b), colour, thickness, cv::LINE_AA, kShift);
}

void Canvas::ellipse(const cv::Point2d& c, double a, double b, double angle_deg, const cv::Scalar& colour,
                     int thickness) {
  const cv::Size axes(std::max(1, cvRound(a * kOne)), std::max(1, cvRound(b * kOne)));
  cv::ellipse(img_, fixed(c), axes, angle_deg, 0, 360, colour, thickness, cv::LINE_AA, kShift);
}

void Canvas::polygon(const std::vector<cv::Point2d>& pts, const cv::Scalar& colour) {
  std::vector<cv::Point> q;
  q.reserve(pts.size());
  for (const auto& p : pts) q.push_back(fixed(p));
  cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{q}, colour, cv::LINE_AA, kShift);
}

void Canvas::text(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, int thickness,
                  int align) {
  const cv::Size sz = text_size(s, scale, thickness);
  const double x = p.x - (align == 1 ? sz.width / 2.0 : align == 2 ? sz.width : 0.0);
  cv::putText(img_, s, cv::Point(cvRound(x - tl_.x), cvRound(p.y - tl_.y)), kFont, scale, colour, thickness,
              cv::LINE_AA);
}

void Canvas::text_centred(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                          int thickness) {
  const cv::Size sz = text_size(s, scale, thickness);
  cv::putText(img_, s, cv::Point(cvRound(p.x - tl_.x - sz.width / 2.0), cvRound(p.y - tl_.y + sz.height / 2.0)),
              kFont, scale, colour, thickness, cv::LINE_AA);
}

void Canvas::label(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                   const cv::Scalar& box) {
  const cv::Size sz = text_size(s, scale, 1);
  const cv::Point2d h(sz.width / 2.0 + 3, sz.height / 2.0 + 3);
  cv::rectangle(img_, fixed(p - h), fixed(p + h), box, cv::FILLED, cv::LINE_8, kShift);
  text_centred(s, p, scale, colour, 1);
}

}  // namespace pbnbv::drawing
