#include "report/canvas.hpp"
#include "core/base/atomic_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace pbnbv::drawing {

namespace {

std::string num(double v) { return fmt::format("{:.2f}", v); }

std::string paint(const std::string& attr, const cv::Scalar& c) { return attr + "=\"" + svg_colour(c) + "\""; }

// The SVG stroke width of an OpenCV thickness (OpenCV's 1 is a 1-px line, t > 1 a t-px one).
std::string stroke(const cv::Scalar& c, int thickness) {
  return paint("stroke", c) + " stroke-width=\"" + std::to_string(std::max(1, thickness)) + "\"";
}

}  // namespace

cv::Size text_size(const std::string& s, double scale, int thickness, int* baseline) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(s, kFont, scale, thickness, &base);
  if (baseline) *baseline = base;
  return sz;
}

std::string svg_colour(const cv::Scalar& bgr) {
  auto c = [](double v) { return std::clamp(static_cast<int>(std::lround(v)), 0, 255); };
  return fmt::format("#{:02x}{:02x}{:02x}", c(bgr[2]), c(bgr[1]), c(bgr[0]));
}

std::string xml_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

Svg::Svg(int width, int height) : w_(width), h_(height) {}

std::string Svg::clip(const cv::Rect& r) {
  if (r == cv::Rect(0, 0, w_, h_)) return "";
  for (size_t i = 0; i < clips_.size(); ++i) {
    if (clips_[i] == r) return "c" + std::to_string(i);
  }
  const std::string id = "c" + std::to_string(clips_.size());
  clips_.push_back(r);
  defs_.push_back(fmt::format("<clipPath id=\"{}\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/></clipPath>", id,
                              r.x, r.y, r.width, r.height));
  return id;
}

void Svg::add(const std::string& element, const std::string& clip_id) {
  if (clip_id.empty()) {
    body_.push_back(element);
  } else if (element.find(" transform=") != std::string::npos) {
    // A clip path is in the user space of the element that uses it, transform included: clip a
    // group around the transformed element instead.
    body_.push_back("<g clip-path=\"url(#" + clip_id + ")\">" + element + "</g>");
  } else {
    // element is "<name ...": insert the clip after the name.
    const size_t sp = element.find(' ');
    body_.push_back(element.substr(0, sp) + " clip-path=\"url(#" + clip_id + ")\"" + element.substr(sp));
  }
}

std::string Svg::document() const {
  std::string out = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" "
      "viewBox=\"0 0 {0} {1}\" font-family=\"Helvetica, Arial, sans-serif\">\n",
      w_, h_);
  out += "<defs>";
  for (const auto& d : defs_) out += d;
  out += "</defs>\n";
  out += fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n", w_, h_);
  for (const auto& e : body_) out += e + "\n";
  out += "</svg>\n";
  return out;
}

void write_text_file(const std::string& path, const std::string& text, const std::string& what) {
  try {
    write_file_atomic(path, text);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(what + ": " + e.what());
  }
}

std::string svg_path_beside(const std::string& png_path) {
  return std::filesystem::path(png_path).replace_extension(".svg").string();
}

Canvas::Canvas(cv::Mat& image, const cv::Rect& rect, double pixel_centre, Svg* svg)
    : img_(image(rect)), tl_(rect.tl()), centre_(pixel_centre), svg_(svg) {
  if (svg_) clip_ = svg_->clip(rect);
}

void Canvas::line(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness) {
  cv::line(img_, fixed(a), fixed(b), colour, thickness, cv::LINE_AA, kShift);
  if (svg_) {
    svg_->add(fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" {} stroke-linecap=\"round\"/>", num(sx(a.x)),
                          num(sy(a.y)), num(sx(b.x)), num(sy(b.y)), stroke(colour, thickness)),
              clip_);
  }
}

void Canvas::disc(const cv::Point2d& c, double r, const cv::Scalar& colour) {
  cv::circle(img_, fixed(c), cvRound(r * kOne), colour, cv::FILLED, cv::LINE_AA, kShift);
  if (svg_) {
    svg_->add(fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"{}\" {}/>", num(sx(c.x)), num(sy(c.y)), num(r),
                          paint("fill", colour)),
              clip_);
  }
}

void Canvas::ring(const cv::Point2d& c, double r, const cv::Scalar& colour, int thickness) {
  cv::circle(img_, fixed(c), cvRound(r * kOne), colour, thickness, cv::LINE_AA, kShift);
  if (svg_) {
    svg_->add(fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"none\" {}/>", num(sx(c.x)), num(sy(c.y)),
                          num(r), stroke(colour, thickness)),
              clip_);
  }
}

void Canvas::cross(const cv::Point2d& c, double r, const cv::Scalar& colour) {
  line(c + cv::Point2d(-r, -r), c + cv::Point2d(r, r), colour);
  line(c + cv::Point2d(-r, r), c + cv::Point2d(r, -r), colour);
}

void Canvas::rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& colour, int thickness) {
  cv::rectangle(img_, fixed(a), fixed(b), colour, thickness, cv::LINE_AA, kShift);
  if (svg_) {
    const double x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
    const std::string fill = thickness < 0 ? paint("fill", colour) : "fill=\"none\" " + stroke(colour, thickness);
    svg_->add(fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {}/>", num(sx(x0)), num(sy(y0)),
                          num(std::abs(b.x - a.x)), num(std::abs(b.y - a.y)), fill),
              clip_);
  }
}

void Canvas::ellipse(const cv::Point2d& c, double a, double b, double angle_deg, const cv::Scalar& colour,
                     int thickness, double alpha) {
  const cv::Size axes(std::max(1, cvRound(a * kOne)), std::max(1, cvRound(b * kOne)));
  if (alpha < 1.0) {
    const cv::Mat before = img_.clone();
    cv::ellipse(img_, fixed(c), axes, angle_deg, 0, 360, colour, thickness, cv::LINE_AA, kShift);
    cv::addWeighted(img_, alpha, before, 1.0 - alpha, 0.0, img_);
  } else {
    cv::ellipse(img_, fixed(c), axes, angle_deg, 0, 360, colour, thickness, cv::LINE_AA, kShift);
  }
  if (svg_) {
    const std::string paint_it = thickness < 0 ? paint("fill", colour) : "fill=\"none\" " + stroke(colour, thickness);
    const std::string opacity = alpha < 1.0 ? fmt::format(" opacity=\"{:.3f}\"", alpha) : "";
    svg_->add(fmt::format("<ellipse cx=\"0\" cy=\"0\" rx=\"{}\" ry=\"{}\" transform=\"translate({} {}) rotate({})\" "
                          "{}{}/>",
                          num(std::max(a, 1.0 / kOne)), num(std::max(b, 1.0 / kOne)), num(sx(c.x)), num(sy(c.y)),
                          num(angle_deg), paint_it, opacity),
              clip_);
  }
}

void Canvas::polygon(const std::vector<cv::Point2d>& pts, const cv::Scalar& colour, double alpha) {
  std::vector<cv::Point> q;
  q.reserve(pts.size());
  for (const auto& p : pts) q.push_back(fixed(p));
  if (alpha < 1.0) {
    const cv::Mat before = img_.clone();
    cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{q}, colour, cv::LINE_AA, kShift);
    cv::addWeighted(img_, alpha, before, 1.0 - alpha, 0.0, img_);
  } else {
    cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{q}, colour, cv::LINE_AA, kShift);
  }
  if (svg_ && !pts.empty()) {
    std::string list;
    for (const auto& p : pts) list += num(sx(p.x)) + "," + num(sy(p.y)) + " ";
    list.pop_back();
    const std::string opacity = alpha < 1.0 ? fmt::format(" fill-opacity=\"{:.3f}\"", alpha) : "";
    svg_->add("<polygon points=\"" + list + "\" " + paint("fill", colour) + opacity + "/>", clip_);
  }
}

void Canvas::pixel_line(const cv::Point& a, const cv::Point& b, const cv::Scalar& colour) {
  cv::line(img_, a - tl_, b - tl_, colour, 1);
  if (svg_) {
    // Pixel i covers [i, i+1): a 1-px line through the pixel centres, long enough to cover the
    // end pixels.
    const cv::Point2d d(b - a);
    const double n = std::max(1e-9, std::hypot(d.x, d.y));
    const cv::Point2d e = d * (0.5 / n);
    svg_->add(fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" {}/>", num(a.x + 0.5 - e.x),
                          num(a.y + 0.5 - e.y), num(b.x + 0.5 + e.x), num(b.y + 0.5 + e.y), stroke(colour, 1)),
              clip_);
  }
}

void Canvas::fill_rect(const cv::Rect& r, const cv::Scalar& colour) {
  cv::rectangle(img_, cv::Rect(r.tl() - tl_, r.size()), colour, cv::FILLED);
  if (svg_) {
    svg_->add(fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {}/>", r.x, r.y, r.width, r.height,
                          paint("fill", colour)),
              clip_);
  }
}

void Canvas::svg_text(const std::string& s, double left, double baseline, double scale, const cv::Scalar& colour,
                      int thickness, const std::string& transform) {
  if (!svg_ || s.empty()) return;
  // Hershey simplex's capital letters are 22 px high at scale 1, a sans-serif's 0.72 em: the same
  // height; textLength keeps OpenCV's width, so the layout holds in both back ends.
  const cv::Size sz = text_size(s, scale, thickness);
  svg_->add(fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"{}\" textLength=\"{}\" lengthAdjust=\"spacingAndGlyphs\" "
                        "{}{}{}>{}</text>",
                        num(left), num(baseline), num(scale * 22.0 / 0.72), sz.width, paint("fill", colour),
                        thickness > 1 ? " font-weight=\"bold\"" : "",
                        transform.empty() ? "" : " transform=\"" + transform + "\"", xml_escape(s)),
            clip_);
}

void Canvas::text(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour, int thickness,
                  int align) {
  const cv::Size sz = text_size(s, scale, thickness);
  const double x = p.x - (align == 1 ? sz.width / 2.0 : align == 2 ? sz.width : 0.0);
  const cv::Point org(cvRound(x - tl_.x), cvRound(p.y - tl_.y));
  cv::putText(img_, s, org, kFont, scale, colour, thickness, cv::LINE_AA);
  svg_text(s, org.x + tl_.x, org.y + tl_.y + 0.5, scale, colour, thickness);
}

void Canvas::text_centred(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                          int thickness) {
  const cv::Size sz = text_size(s, scale, thickness);
  const cv::Point org(cvRound(p.x - tl_.x - sz.width / 2.0), cvRound(p.y - tl_.y + sz.height / 2.0));
  cv::putText(img_, s, org, kFont, scale, colour, thickness, cv::LINE_AA);
  svg_text(s, org.x + tl_.x, org.y + tl_.y + 0.5, scale, colour, thickness);
}

void Canvas::text_up(const std::string& s, const cv::Point& centre, double scale, const cv::Scalar& colour,
                     int thickness) {
  if (s.empty()) return;
  int base = 0;
  const cv::Size sz = text_size(s, scale, thickness, &base);
  cv::Mat strip(sz.height + base + 4, sz.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(strip, s, cv::Point(2, 2 + sz.height), kFont, scale, colour, thickness, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Point c = centre - tl_;
  const cv::Point tl(c.x - turned.cols / 2, c.y - turned.rows / 2);
  const cv::Rect dst = cv::Rect(tl, turned.size()) & cv::Rect(0, 0, img_.cols, img_.rows);
  if (!dst.empty()) {
    cv::Mat roi = img_(dst);
    cv::min(roi, turned(cv::Rect(dst.tl() - tl, dst.size())), roi);
  }
  // The strip's text origin (2, 2 + height) turned: x = tl.x + 2 + height, y = tl.y + rows - 2.
  const double ox = tl.x + tl_.x + 2.0 + sz.height, oy = tl.y + tl_.y + turned.rows - 2.0;
  svg_text(s, ox, oy, scale, colour, thickness, fmt::format("rotate(-90 {} {})", num(ox), num(oy)));
}

void Canvas::label(const std::string& s, const cv::Point2d& p, double scale, const cv::Scalar& colour,
                   const cv::Scalar& box) {
  const cv::Size sz = text_size(s, scale, 1);
  const cv::Point2d h(sz.width / 2.0 + 3, sz.height / 2.0 + 3);
  cv::rectangle(img_, fixed(p - h), fixed(p + h), box, cv::FILLED, cv::LINE_8, kShift);
  if (svg_) {
    svg_->add(fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {}/>", num(sx(p.x - h.x)),
                          num(sy(p.y - h.y)), num(2 * h.x), num(2 * h.y), paint("fill", box)),
              clip_);
  }
  text_centred(s, p, scale, colour, 1);
}

}  // namespace pbnbv::drawing
