// Hand-eye and turntable calibration from a sphere of known radius. See calibration.hpp.
#include "core/rig/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include <pugixml.hpp>

namespace pbnbv {

namespace {

// The two centres of spheres of radius r through three points; false when none exists.
bool centres_through(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double r,
                     Eigen::Vector3d* c1, Eigen::Vector3d* c2) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const Eigen::Vector3d n = ab.cross(ac);
  const double n2 = n.squaredNorm();
  if (n2 < 1e-16) return false;  // collinear
  // Circumcentre of the triangle.
  const Eigen::Vector3d o = a + (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (2.0 * n2);
  const double h2 = r * r - (o - a).squaredNorm();
  if (h2 < 0) return false;
  const Eigen::Vector3d off = std::sqrt(h2) * n / std::sqrt(n2);
  *c1 = o + off;
  *c2 = o - off;
  return true;
}

// Gauss-Newton for the centre of a sphere of radius r through `points`.
Eigen::Vector3d refine_centre(const std::vector<Eigen::Vector3d>& points, double r, Eigen::Vector3d c) {
  for (int it = 0; it < 20; ++it) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d d = p - c;
      const double len = d.norm();
      if (len < 1e-12) continue;
      const Eigen::Vector3d j = -d / len;  // d(|p - c| - r)/dc
      jtj += j * j.transpose();
      jtr += j * (len - r);
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
    c += step;
    if (step.norm() < 1e-12) break;
  }
  return c;
}

std::vector<Eigen::Vector3d> inliers_of(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& c,
                                        double r, double tol) {
  std::vector<Eigen::Vector3d> in;
  for (const Eigen::Vector3d& p : points) {
    if (std::abs((p - c).norm() - r) < tol) in.push_back(p);
  }
  return in;
}

// Small rotation (rotation vector) and translation as a pose.
Pose exp_pose(const Eigen::Vector3d& w, const Eigen::Vector3d& v) {
  Pose p = Pose::Identity();
  const double a = w.norm();
  if (a > 0) p.linear() = Eigen::AngleAxisd(a, w / a).toRotationMatrix();
  p.translation() = v;
  return p;
}

constexpr int kUnknowns = 12;  // hand-eye 6, axis offset 3, tilt 2, zero 1
using Params = Eigen::Matrix<double, kUnknowns, 1>;

struct Model {
  const RigModel& rig;
  Eigen::Vector3d centre_in_mount;
  // The rig with parameters x applied: its hand-eye and zero, and the turntable correction.
  RigModel apply(const Params& x, Pose* correction) const {
    RigModel r = rig;
    r.flange_T_camera = rig.flange_T_camera * exp_pose(x.segment<3>(0), x.segment<3>(3));
    *correction = exp_pose(Eigen::Vector3d(x[9], x[10], 0.0), Eigen::Vector3d::Zero());
    correction->translation() = x.segment<3>(6);
    r.turntable_zero_rad = rig.turntable_zero_rad + x[11];
    return r;
  }
  Eigen::VectorXd residuals(const Params& x, const std::vector<SphereObservation>& obs,
                            const std::vector<bool>& used) const {
    Pose corr;
    const RigModel r = apply(x, &corr);
    Eigen::VectorXd res = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(obs.size()));
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (!used[i]) continue;
      res.segment<3>(3 * static_cast<Eigen::Index>(i)) =
          predicted_sphere_centre(r, corr, centre_in_mount, obs[i]) - obs[i].centre_in_camera;
    }
    return res;
  }
};

double rms_of(const std::vector<double>& r, const std::vector<bool>& used) {
  double s = 0;
  int n = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!used[i]) continue;
    s += r[i] * r[i];
    ++n;
  }
  return n > 0 ? std::sqrt(s / n) : 0.0;
}

// Levenberg-Marquardt on the free parameters (the others stay 0); numerical Jacobian.
Params levenberg_marquardt(const Model& model, const std::vector<SphereObservation>& obs,
                           const std::vector<bool>& used, const std::vector<int>& free, int max_iterations,
                           int* iterations) {
  Params x = Params::Zero();
  Eigen::VectorXd r = model.residuals(x, obs, used);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  const double h = 1e-7;
  *iterations = 0;
  for (int it = 0; it < max_iterations; ++it) {
    ++*iterations;
    Eigen::MatrixXd j(r.size(), static_cast<Eigen::Index>(free.size()));
    for (std::size_t k = 0; k < free.size(); ++k) {
      Params xp = x, xm = x;
      xp[free[k]] += h;
      xm[free[k]] -= h;
      j.col(static_cast<Eigen::Index>(k)) = (model.residuals(xp, obs, used) - model.residuals(xm, obs, used)) / (2 * h);
    }
    const Eigen::MatrixXd jtj = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * r;
    bool improved = false;
    Eigen::VectorXd step;
    for (int tries = 0; tries < 20; ++tries) {
      Eigen::MatrixXd a = jtj;
      a.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
      step = a.ldlt().solve(-g);
      Params xn = x;
      for (std::size_t k = 0; k < free.size(); ++k) xn[free[k]] += step[static_cast<Eigen::Index>(k)];
      const Eigen::VectorXd rn = model.residuals(xn, obs, used);
      if (rn.squaredNorm() <= cost) {
        x = xn;
        r = rn;
        cost = rn.squaredNorm();
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        break;
      }
      lambda *= 10;
    }
    if (!improved || step.norm() < 1e-13) break;
  }
  return x;
}

std::string fmt17(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

}  // namespace

SphereFit fit_sphere_known_radius(const std::vector<Eigen::Vector3d>& points, double radius_m,
                                  const SphereFitOptions& o) {
  SphereFit fit;
  if (!(radius_m > 0)) throw std::invalid_argument("sphere radius " + std::to_string(radius_m) + " m is not positive");
  if (static_cast<int>(points.size()) < o.min_inliers) {
    fit.why = std::to_string(points.size()) + " points, fewer than the " + std::to_string(o.min_inliers) + " needed";
    return fit;
  }
  std::mt19937_64 rng(o.seed);
  // Hypotheses are scored on at most 4000 points spread over the set.
  std::vector<Eigen::Vector3d> sample;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 4000);
  for (std::size_t i = 0; i < points.size(); i += stride) sample.push_back(points[i]);
  std::uniform_int_distribution<std::size_t> pick(0, sample.size() - 1);
  int best = -1;
  Eigen::Vector3d best_c = Eigen::Vector3d::Zero();
  for (int it = 0; it < o.iterations; ++it) {
    const Eigen::Vector3d& a = sample[pick(rng)];
    // The other two near the first (within a sphere's diameter): far points are rarely on the
    // same sphere.
    Eigen::Vector3d b, c;
    int found = 0;
    for (int t = 0; t < 50 && found < 2; ++t) {
      const Eigen::Vector3d& p = sample[pick(rng)];
      const double d = (p - a).norm();
      if (d < 0.2 * radius_m || d > 2 * radius_m) continue;
      (found == 0 ? b : c) = p;
      ++found;
    }
    if (found < 2) continue;
    Eigen::Vector3d c1, c2;
    if (!centres_through(a, b, c, radius_m, &c1, &c2)) continue;
    const Eigen::Vector3d centre = c1.norm() > c2.norm() ? c1 : c2;  // behind the seen surface
    int n = 0;
    for (const Eigen::Vector3d& p : sample) n += std::abs((p - centre).norm() - radius_m) < o.inlier_m;
    if (n > best) {
      best = n;
      best_c = centre;
    }
  }
  if (best < 0) {
    fit.why = "no three points on a sphere of radius " + std::to_string(radius_m) + " m";
    return fit;
  }
  // Least squares on the inliers, the band narrowing to 3 x their rms (a stray point near the
  // surface then stops pulling the centre), never below 0.1 mm.
  Eigen::Vector3d centre = best_c;
  std::vector<Eigen::Vector3d> in;
  double band = o.inlier_m;
  for (int round = 0; round < 8; ++round) {
    in = inliers_of(points, centre, radius_m, band);
    if (static_cast<int>(in.size()) < 4) break;
    centre = refine_centre(in, radius_m, centre);
    double s2 = 0;
    for (const Eigen::Vector3d& p : in) s2 += std::pow((p - centre).norm() - radius_m, 2);
    band = std::min(o.inlier_m, std::max(3 * std::sqrt(s2 / in.size()), 1e-4));
  }
  in = inliers_of(points, centre, radius_m, o.inlier_m);
  fit.centre = centre;
  fit.inliers = static_cast<int>(in.size());
  double s = 0;
  Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : in) {
    const double e = (p - centre).norm() - radius_m;
    s += e * e;
    mean_normal += (p - centre).normalized();
  }
  fit.rms_m = in.empty() ? 0.0 : std::sqrt(s / in.size());
  fit.cap_spread = in.empty() ? 0.0 : 1.0 - mean_normal.norm() / in.size();
  if (fit.inliers < o.min_inliers) {
    fit.why = "only " + std::to_string(fit.inliers) + " points within " + std::to_string(o.inlier_m * 1e3) +
              " mm of the best sphere (" + std::to_string(o.min_inliers) + " needed)";
  } else if (fit.cap_spread < o.min_cap_spread) {
    fit.why = "the best sphere's points are a small patch (spread " + std::to_string(fit.cap_spread) +
              "), not a sphere's visible side";
  } else {
    fit.ok = true;
  }
  return fit;
}

Eigen::Vector3d predicted_sphere_centre(const RigModel& rig, const Pose& turntable_correction,
                                        const Eigen::Vector3d& centre_in_mount, const SphereObservation& o) {
  Pose world_T_mount = rig.world_T_turntable * turntable_correction;
  world_T_mount.linear() =
      world_T_mount.linear() * Eigen::AngleAxisd(o.turntable_rad - rig.turntable_zero_rad, Eigen::Vector3d::UnitZ());
  return camera_in_world(rig, o.q).inverse() * (world_T_mount * centre_in_mount);
}

RigCalibration solve_rig_calibration(const RigModel& rig, const Eigen::Vector3d& centre_in_mount,
                                     const std::vector<SphereObservation>& obs, const CalibrationSolveOptions& o) {
  if (rig.kind != RigKind::kArm || !rig.has_turntable) {
    throw std::invalid_argument("calibration needs an arm rig with a turntable (" + rig.model_path + ")");
  }
  std::vector<int> free{0, 1, 2, 3, 4, 5, 11};
  if (o.fit_axis) free = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  const std::size_t needed = o.fit_axis ? 4 : 3;  // 3 equations each
  if (obs.size() < needed) {
    throw std::invalid_argument(std::to_string(obs.size()) + " sphere observations, at least " +
                                std::to_string(needed) + " are needed (more, from varied poses, for a good fit)");
  }
  const Model model{rig, centre_in_mount};
  RigCalibration out;
  out.used.assign(obs.size(), true);
  auto per_frame = [&](const Params& x) {
    const Eigen::VectorXd r = model.residuals(x, obs, std::vector<bool>(obs.size(), true));
    std::vector<double> v(obs.size());
    for (std::size_t i = 0; i < obs.size(); ++i) v[i] = r.segment<3>(3 * static_cast<Eigen::Index>(i)).norm();
    return v;
  };
  out.residual_before_m = per_frame(Params::Zero());
  Params x = levenberg_marquardt(model, obs, out.used, free, o.max_iterations, &out.iterations);
  // One round of outlier rejection (a frame whose sphere fit went wrong), then solve again.
  std::vector<double> after = per_frame(x);
  std::vector<double> sorted = after;
  std::sort(sorted.begin(), sorted.end());
  const double limit = std::max(o.outlier_factor * sorted[sorted.size() / 2], o.outlier_floor_m);
  int dropped = 0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (after[i] > limit) {
      out.used[i] = false;
      ++dropped;
    }
  }
  if (dropped > 0 && obs.size() - dropped >= needed) {
    int more = 0;
    x = levenberg_marquardt(model, obs, out.used, free, o.max_iterations, &more);
    out.iterations += more;
  } else {
    out.used.assign(obs.size(), true);
  }
  out.residual_after_m = per_frame(x);
  out.rms_before_m = rms_of(out.residual_before_m, out.used);
  out.rms_after_m = rms_of(out.residual_after_m, out.used);
  const RigModel calibrated = model.apply(x, &out.turntable_correction);
  out.flange_T_camera = calibrated.flange_T_camera;
  out.turntable_zero_rad = calibrated.turntable_zero_rad;
  const Pose w = rig.world_T_turntable * out.turntable_correction;
  out.axis_direction_world = w.linear().col(2);
  out.axis_point_world = w.translation();
  return out;
}

std::string calibrated_rig_xml(const std::string& xml, const std::string& path, const Pose& flange_T_camera,
                               double turntable_zero_rad) {
  // Parsed as XML (comments and whitespace kept, written back as they were): a comment or a
  // string that only looks like an element is never edited.
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed =
      doc.load_buffer(xml.data(), xml.size(), pugi::parse_default | pugi::parse_comments | pugi::parse_ws_pcdata |
                                                  pugi::parse_declaration | pugi::parse_doctype);
  if (!parsed) {
    throw std::runtime_error(path + ": not well-formed XML at byte " + std::to_string(parsed.offset) + " (" +
                             parsed.description() + ")");
  }
  pugi::xml_node root = doc.child("mujoco");
  if (!root) throw std::runtime_error(path + ": no <mujoco> element at the top");
  pugi::xml_node camera = root.find_node([](const pugi::xml_node& n) {
    return std::string(n.name()) == "body" && std::string(n.attribute("name").value()) == "camera_optical";
  });
  if (!camera) throw std::runtime_error(path + ": no <body name=\"camera_optical\"> to calibrate");
  // Its pose: every way MJCF can give an orientation removed, pos and quat written.
  for (const char* a : {"pos", "quat", "xyaxes", "zaxis", "axisangle", "euler"}) camera.remove_attribute(a);
  const Eigen::Vector3d t = flange_T_camera.translation();
  Eigen::Quaterniond q(flange_T_camera.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;
  pugi::xml_attribute pos = camera.insert_attribute_after("pos", camera.attribute("name"));
  pos.set_value((fmt17(t.x()) + " " + fmt17(t.y()) + " " + fmt17(t.z())).c_str());
  camera.insert_attribute_after("quat", pos)
      .set_value((fmt17(q.w()) + " " + fmt17(q.x()) + " " + fmt17(q.y()) + " " + fmt17(q.z())).c_str());
  // The turntable's zero: replaced where it is, else added to the first <custom> (made when the
  // file has none).
  pugi::xml_node zero = root.find_node([](const pugi::xml_node& n) {
    return std::string(n.name()) == "numeric" && std::string(n.attribute("name").value()) == "pbnbv_turntable_zero" &&
           std::string(n.parent().name()) == "custom";
  });
  if (!zero) {
    pugi::xml_node custom = root.child("custom");
    if (!custom) {
      custom = root.append_child("custom");
      custom.append_child(pugi::node_pcdata).set_value("\n  ");
      root.append_child(pugi::node_pcdata).set_value("\n");
    }
    // Indented as the section's first child is (or two spaces deeper than the section).
    const pugi::xml_node first = custom.first_child();
    const std::string indent = first.type() == pugi::node_pcdata ? first.value() : std::string("\n    ");
    custom.prepend_child(pugi::node_pcdata).set_value(indent.c_str());
    zero = custom.prepend_child("numeric");
    custom.prepend_child(pugi::node_pcdata).set_value(indent.c_str());
    custom.prepend_child(pugi::node_comment).set_value(" pbnbv calibrate: the turntable's reading at the platter's zero, rad ");
    custom.prepend_child(pugi::node_pcdata).set_value(indent.c_str());
    zero.append_attribute("name").set_value("pbnbv_turntable_zero");
  }
  if (!zero.attribute("data")) zero.append_attribute("data");
  zero.attribute("data").set_value(fmt17(turntable_zero_rad).c_str());
  // Top-level nodes (the declaration, header comments, <mujoco>) one per line, as pugixml keeps
  // no whitespace between them.
  std::ostringstream out;
  for (const pugi::xml_node& n : doc.children()) {
    n.print(out, "", pugi::format_raw);
    out << "\n";
  }
  return out.str();
}

}  // namespace pbnbv
