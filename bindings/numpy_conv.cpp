#include "numpy_conv.hpp"

#include <cmath>

namespace mgn::py_conv {

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

Vec3d to_vec3(const py::handle& obj, const char* arg) {
  const auto rows = to_rows<double, 3>(
      py::module_::import("numpy").attr("reshape")(obj, py::make_tuple(-1, 3)), arg);
  if (rows.rows() != 1)
    throw_error<InvalidArgument>(arg, ": expected 3 numbers, got ", 3 * rows.rows());
  return rows.row(0).transpose();
}

namespace {
Pose checked_pose(const double* p, const char* arg, py::ssize_t index, bool batched) {
  const std::string where =
      batched ? std::string(arg) + "[" + std::to_string(index) + "]" : std::string(arg);
  Mat4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = p[4 * r + c];
  if (!M.allFinite())
    throw_error<InvalidArgument>(
        where, ": pose has non-finite entries (NaN or Inf); expected a finite 4x4 rigid transform");
  if (std::abs(M(3, 0)) > 1e-9 || std::abs(M(3, 1)) > 1e-9 || std::abs(M(3, 2)) > 1e-9 ||
      std::abs(M(3, 3) - 1.0) > 1e-9) {
    throw_error<InvalidArgument>(where, ": last row is [", M(3, 0), ", ", M(3, 1), ", ", M(3, 2),
                                 ", ", M(3, 3), "]; expected [0, 0, 0, 1]");
  }
  const Mat3d R = M.topLeftCorner<3, 3>();
  const double ortho = (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho > 1e-6 || R.determinant() < 0.0) {
    throw_error<InvalidArgument>(
        where, ": rotation block is not a proper rotation (|R^T R - I| = ", ortho,
        ", det = ", R.determinant(), "); expected an orthonormal matrix with det +1");
  }
  Pose X = Pose::Identity();
  X.linear() = R;
  X.translation() = M.topRightCorner<3, 1>();
  return X;
}
}  // namespace

std::vector<Pose> to_poses(const py::handle& obj, const char* arg) {
  CArray<double> a;
  try {
    a = py::cast<CArray<double>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(arg, ": expected a float array of shape (4, 4) or (N, 4, 4)");
  }
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4)
    return {checked_pose(a.data(), arg, 0, false)};
  if (a.ndim() != 3 || a.shape(1) != 4 || a.shape(2) != 4) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
      shape += (i ? ", " : "") + std::to_string(a.shape(i));
    throw_error<InvalidArgument>(arg, ": expected shape (4, 4) or (N, 4, 4), got ", shape, ")");
  }
  std::vector<Pose> out;
  out.reserve(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    out.push_back(checked_pose(a.data() + 16 * i, arg, i, true));
  return out;
}

Pose to_pose(const py::handle& obj, const char* arg) {
  CArray<double> a;
  try {
    a = py::cast<CArray<double>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(arg, ": expected a float array of shape (4, 4)");
  }
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw_error<InvalidArgument>(arg, ": expected shape (4, 4)");
  }
  return checked_pose(a.data(), arg, 0, false);
}

py::array pose_to_numpy(const Pose& X) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M = X.matrix();
  py::array_t<double> out({4, 4});
  std::copy(M.data(), M.data() + 16, out.mutable_data());
  return out;
}

py::array poses_to_numpy(const std::vector<Pose>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto a = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Mat4d M = poses[k].matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) a(static_cast<py::ssize_t>(k), r, c) = M(r, c);
  }
  return out;
}

}  // namespace mgn::py_conv
