#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/camera.hpp>

#include <cmath>

namespace mgn {

namespace {

constexpr double kPi = 3.14159265358979323846;

void check_finite(const Vec3d& v, const char* what, const char* name) {
  if (!v.allFinite()) {
    throw_error<InvalidArgument>(what, ": ", name, " must be finite, got (", v.x(), ", ", v.y(),
                                 ", ", v.z(), ")");
  }
}

/// Camera at target + R (cos phi sin theta, sin phi sin theta, cos theta) looking at the target.
Pose pose_on_sphere(const Vec3d& target, double R, double theta, double phi) {
  const Vec3d dir(std::cos(phi) * std::sin(theta), std::sin(phi) * std::sin(theta),
                  std::cos(theta));
  // Straight down (or nearly): world +z is parallel to the view axis, use +y as "up" instead.
  const Vec3d up = std::sin(theta) < 1e-9 ? Vec3d::UnitY() : Vec3d::UnitZ();
  return look_at(target + R * dir, target, up);
}

}  // namespace

Intrinsics Intrinsics::mgn_synthetic() {
  Intrinsics k;
  k.width = 1200;
  k.height = 1200;
  k.fx = k.fy = 1200.0 * 35.0 / 20.955;
  k.cx = 600.0;
  k.cy = 600.0;
  return k;
}

Intrinsics Intrinsics::zivid_two_like() {
  Intrinsics k;
  k.width = 1944;
  k.height = 1200;
  k.fx = k.fy = 1780.0;
  k.cx = 972.0;
  k.cy = 600.0;
  return k;
}

Mat3d Intrinsics::K() const {
  Mat3d m = Mat3d::Identity();
  m(0, 0) = fx;
  m(1, 1) = fy;
  m(0, 2) = cx;
  m(1, 2) = cy;
  return m;
}

void Intrinsics::validate(const char* what) const {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    throw_error<InvalidArgument>(what, ": image size must be in 1..16384 px, got ", width, "x",
                                 height);
  }
  if (!(std::isfinite(fx) && fx > 0.0) || !(std::isfinite(fy) && fy > 0.0)) {
    throw_error<InvalidArgument>(what, ": focal lengths must be finite and > 0 px, got fx=", fx,
                                 " fy=", fy);
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    throw_error<InvalidArgument>(what, ": principal point must be finite, got cx=", cx, " cy=", cy);
  }
}

void CameraView::validate(const char* what) const {
  K.validate(what);
  const Mat4d& M = X_WC.matrix();
  if (!M.allFinite()) throw_error<InvalidArgument>(what, ": X_WC has non-finite entries");
  const Mat3d R = X_WC.linear();
  const double orth = (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-6 || R.determinant() < 0.0) {
    throw_error<InvalidArgument>(what,
                                 ": X_WC rotation must be orthonormal and right-handed (error ",
                                 orth, ", det ", R.determinant(), ")");
  }
}

Pose look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up) {
  check_finite(eye, "look_at", "eye");
  check_finite(target, "look_at", "target");
  check_finite(up, "look_at", "up");
  const Vec3d d = target - eye;
  if (d.norm() < 1e-12) throw_error<InvalidArgument>("look_at: eye and target coincide");
  if (up.norm() < 1e-12) throw_error<InvalidArgument>("look_at: up must be non-zero");
  const Vec3d z = d.normalized();
  const Vec3d xr = z.cross(up.normalized());
  if (xr.norm() < 1e-9) {
    throw_error<InvalidArgument>("look_at: up (", up.x(), ", ", up.y(), ", ", up.z(),
                                 ") is parallel to the viewing direction; pick another up");
  }
  const Vec3d x = xr.normalized();
  const Vec3d y = z.cross(x);
  Pose X = Pose::Identity();
  X.linear().col(0) = x;
  X.linear().col(1) = y;
  X.linear().col(2) = z;
  X.translation() = eye;
  return X;
}

std::vector<Pose> mgn_rig_from_params(const MgnRigParams& p, const Vec3d& target) {
  check_finite(target, "mgn_rig", "target");
  const double vals[] = {p.R_start, p.R_end, p.theta_start, p.theta_end, p.phi_end};
  for (double v : vals) {
    if (!std::isfinite(v)) throw_error<InvalidArgument>("mgn_rig: parameters must be finite");
  }
  if (!(p.R_start > 0.0) || !(p.R_end > 0.0)) {
    throw_error<InvalidArgument>("mgn_rig: radii must be > 0 m, got R_start=", p.R_start,
                                 " R_end=", p.R_end);
  }
  for (double t : {p.theta_start, p.theta_end}) {
    if (t < 0.0 || t >= 0.5 * kPi) {
      throw_error<InvalidArgument>("mgn_rig: tilts must be in [0, pi/2) rad, got ", t);
    }
  }
  std::vector<Pose> poses;
  poses.reserve(37);
  poses.push_back(pose_on_sphere(target, p.R_start, 0.0, 0.0));
  for (int iR = 0; iR < 3; ++iR) {
    const double R = p.R_start + iR * (p.R_end - p.R_start) / 2.0;
    for (int it = 0; it < 3; ++it) {
      const double theta = p.theta_start + it * (p.theta_end - p.theta_start) / 2.0;
      for (int ip = 0; ip < 4; ++ip) {
        const double phi = ip * p.phi_end / 4.0;
        poses.push_back(pose_on_sphere(target, R, theta, phi));
      }
    }
  }
  return poses;
}

std::vector<Pose> mgn_rig(std::uint64_t seed, const Vec3d& target, MgnRigParams* params) {
  Rng rng(seed, 0);
  MgnRigParams p;
  p.R_start = rng.uniform(0.70, 0.80);
  p.R_end = rng.uniform(1.00, 1.40);
  p.theta_start = rng.uniform(0.3, 0.8);
  p.theta_end = rng.uniform(0.1, 0.3);
  p.phi_end = rng.uniform(kPi, 2.0 * kPi);
  std::vector<Pose> poses = mgn_rig_from_params(p, target);
  if (params) *params = p;
  return poses;
}

std::vector<Pose> hemisphere_rig(const std::vector<double>& radii, const std::vector<double>& tilts,
                                 const std::vector<double>& azimuths, const Vec3d& target) {
  check_finite(target, "hemisphere_rig", "target");
  if (radii.empty() || tilts.empty() || azimuths.empty()) {
    throw_error<InvalidArgument>(
        "hemisphere_rig: radii, tilts and azimuths must be non-empty, "
        "got ",
        radii.size(), ", ", tilts.size(), ", ", azimuths.size());
  }
  for (double r : radii) {
    if (!(std::isfinite(r) && r > 0.0))
      throw_error<InvalidArgument>("hemisphere_rig: radii must be finite and > 0 m, got ", r);
  }
  for (double t : tilts) {
    if (!(std::isfinite(t) && t >= 0.0 && t <= 0.5 * kPi))
      throw_error<InvalidArgument>("hemisphere_rig: tilts must be in [0, pi/2] rad, got ", t);
  }
  for (double a : azimuths) {
    if (!std::isfinite(a))
      throw_error<InvalidArgument>("hemisphere_rig: azimuths must be finite, got ", a);
  }
  std::vector<Pose> poses;
  poses.reserve(radii.size() * tilts.size() * azimuths.size());
  for (double r : radii)
    for (double t : tilts)
      for (double a : azimuths) poses.push_back(pose_on_sphere(target, r, t, a));
  return poses;
}

}  // namespace mgn
