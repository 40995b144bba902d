#pragma once
/// @file camera.hpp  Pinhole intrinsics, camera views and camera rigs (docs/models.md §6).
///
/// Camera frame C is OpenCV: x right, y down, z forward (the optical axis). A pixel (u, v) has its
/// centre at image coordinates (u + 0.5, v + 0.5), so a point p_C projects to
/// (fx * x / z + cx, fy * y / z + cy) in continuous image coordinates; this is the same model as
/// mgn::camera_rays (raytrace/ray_scene.hpp), so a rendered pixel and a ray cast through it agree.
/// Poses X_WC are the camera pose in the world W (maps camera coordinates to world coordinates).
/// Lengths in metres, angles in radians, intrinsics in pixels.

#include <mgn/core/types.hpp>

#include <cstdint>
#include <vector>

namespace mgn {

/// Pinhole intrinsics in pixels (no distortion).
struct Intrinsics {
  int width = 0;    ///< image width, px (> 0)
  int height = 0;   ///< image height, px (> 0)
  double fx = 0.0;  ///< focal length along x, px (> 0)
  double fy = 0.0;  ///< focal length along y, px (> 0)
  double cx = 0.0;  ///< principal point x, px (continuous image coordinates)
  double cy = 0.0;  ///< principal point y, px

  /// The MetaGraspNet synthetic camera: 1200 x 1200, 35 mm focal length on a 20.955 mm aperture
  /// (fx = fy = 1200 * 35 / 20.955 ~= 2004.3 px), principal point at the image centre.
  static Intrinsics mgn_synthetic();
  /// An industrial structured-light camera similar to a Zivid Two: 1944 x 1200 px,
  /// fx = fy = 1780 px (about 57 x 37 degrees field of view), principal point at the centre.
  /// Approximate values, not a calibration of a real device.
  static Intrinsics zivid_two_like();

  /// The 3x3 matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]].
  Mat3d K() const;
  /// Throws InvalidArgument (naming `what`) unless width, height > 0, fx, fy > 0 and finite, and
  /// cx, cy finite.
  void validate(const char* what = "Intrinsics") const;
};

/// A camera: intrinsics and pose of the camera frame C (OpenCV) in the world W.
struct CameraView {
  Intrinsics K;
  Pose X_WC = Pose::Identity();
  /// Throws InvalidArgument if the intrinsics are invalid or X_WC is not a finite rigid transform.
  void validate(const char* what = "CameraView") const;
};

/// Camera pose at `eye` looking at `target` (world frame, m). The image "up" (-y of the camera)
/// points as close as possible to `up`. Throws InvalidArgument if a value is not finite, eye ==
/// target, or `up` is (nearly) parallel to the viewing direction.
Pose look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up = Vec3d::UnitZ());

/// The random parameters of one MetaGraspNet rig (docs/models.md §6).
struct MgnRigParams {
  double R_start = 0.0;      ///< radius of view 0 and of the first ring, m, ~ U(0.70, 0.80)
  double R_end = 0.0;        ///< radius of the last ring, m, ~ U(1.00, 1.40)
  double theta_start = 0.0;  ///< tilt from the vertical of the first tilt ring, rad, ~ U(0.3, 0.8)
  double theta_end = 0.0;    ///< tilt of the last tilt ring, rad, ~ U(0.1, 0.3)
  double phi_end = 0.0;      ///< azimuth span, rad, ~ U(pi, 2 pi)
};

/// The 37 MetaGraspNet views around `target` (world frame, m), drawn from Rng(seed, 0) in the
/// order R_start, R_end, theta_start, theta_end, phi_end. View 0 looks straight down from
/// target + R_start * z (image x = world x, image down = world -y). View v = 1 + 12 i_R + 4 i_theta
/// + i_phi (i_R, i_theta in 0..2, i_phi in 0..3) sits at target + R (cos phi sin theta,
/// sin phi sin theta, cos theta) with R = R_start + i_R (R_end - R_start) / 2,
/// theta = theta_start + i_theta (theta_end - theta_start) / 2, phi = i_phi * phi_end / 4, and
/// looks at the target with world +z as "up". If `params` is not null the drawn values are
/// stored there.
std::vector<Pose> mgn_rig(std::uint64_t seed, const Vec3d& target, MgnRigParams* params = nullptr);
/// The 37 views of given rig parameters (validated: radii > 0, tilts in [0, pi/2)).
std::vector<Pose> mgn_rig_from_params(const MgnRigParams& params, const Vec3d& target);

/// Cameras on a hemisphere around `target`: one per (radius, tilt, azimuth) combination, ordered
/// radius-major then tilt then azimuth (index = (i_r * n_tilt + i_t) * n_azimuth + i_a). Tilt is
/// measured from the vertical (0 = straight down, at most pi/2), azimuth from world +x towards +y.
/// Throws InvalidArgument on an empty list, a radius <= 0, a tilt outside [0, pi/2] or a
/// non-finite value.
std::vector<Pose> hemisphere_rig(const std::vector<double>& radii, const std::vector<double>& tilts,
                                 const std::vector<double>& azimuths, const Vec3d& target);

}  // namespace mgn
