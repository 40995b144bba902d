#pragma once
// numpy <-> Eigen conversions shared by the bind_*.cpp files. Inputs are validated here (shape,
// finiteness of poses) so that errors name the Python argument; outputs are moved into numpy
// arrays without copies (a capsule owns the buffer).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <mgn/core/error.hpp>
#include <mgn/core/types.hpp>

#include <string>
#include <utility>
#include <vector>

namespace mgn::py_conv {

namespace py = pybind11;

template <typename T>
using CArray = py::array_t<T, py::array::c_style | py::array::forcecast>;

/// "(2, 3)"-style text of an array's shape, for error messages.
std::string shape_of(const py::array& a);

/// 3 numbers (any array-like of 3 values) -> Vec3d. Names `arg` in errors.
Vec3d to_vec3(const py::handle& obj, const char* arg);

/// (N,cols) array -> row-major Eigen matrix (copy). Names `arg` in errors.
template <typename Scalar, int Cols>
Eigen::Matrix<Scalar, Eigen::Dynamic, Cols, Eigen::RowMajor> to_rows(const py::handle& obj,
                                                                     const char* arg) {
  CArray<Scalar> a;
  try {
    a = py::cast<CArray<Scalar>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(arg, ": expected a numeric array of shape (N, ", Cols, ")");
  }
  if (a.ndim() != 2 || a.shape(1) != Cols)
    throw_error<InvalidArgument>(arg, ": expected an array of shape (N, ", Cols, "), got shape ",
                                 shape_of(a));
  using M = Eigen::Matrix<Scalar, Eigen::Dynamic, Cols, Eigen::RowMajor>;
  return Eigen::Map<const M>(a.data(), a.shape(0), Cols);
}

/// Moves a row-major Eigen matrix into a numpy array (no copy).
template <typename Derived>
py::array to_numpy(Derived&& m) {
  using M = std::decay_t<Derived>;
  auto* heap = new M(std::forward<Derived>(m));
  py::capsule owner(heap, [](void* p) { delete static_cast<M*>(p); });
  using Scalar = typename M::Scalar;
  if (M::ColsAtCompileTime == 1) {
    return py::array_t<Scalar>({static_cast<py::ssize_t>(heap->rows())}, heap->data(), owner);
  }
  return py::array_t<Scalar>(
      {static_cast<py::ssize_t>(heap->rows()), static_cast<py::ssize_t>(heap->cols())},
      heap->data(), owner);
}

/// Read-only numpy view (no copy) of a row-major Eigen matrix owned by `owner` (e.g. the Python
/// object of a Mesh), which the view keeps alive.
template <typename M>
py::array view_of(const M& mat, py::handle owner) {
  using Scalar = typename M::Scalar;
  py::array_t<Scalar> arr(
      {static_cast<py::ssize_t>(mat.rows()), static_cast<py::ssize_t>(mat.cols())}, mat.data(),
      owner);
  arr.attr("setflags")(py::arg("write") = false);
  return arr;
}

/// Moves a std::vector into a 1-D numpy array (no copy). uint8 "bool" vectors become bool arrays.
template <typename T>
py::array to_numpy(std::vector<T>&& v) {
  auto* heap = new std::vector<T>(std::move(v));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>({static_cast<py::ssize_t>(heap->size())}, heap->data(), owner);
}

inline py::array to_bool_numpy(std::vector<std::uint8_t>&& v) {
  py::array arr = to_numpy(std::move(v));
  return arr.attr("view")(py::dtype::of<bool>());
}

/// A flat row-major image array viewed as (h, w) or, for c > 1, (h, w, c) (no copy).
inline py::array as_image(const py::array& flat, int h, int w, int c = 1) {
  if (c == 1) return flat.attr("reshape")(h, w);
  return flat.attr("reshape")(h, w, c);
}

/// Moves an (h*w*c) vector into an (h, w[, c]) numpy array without copying; None when the
/// vector is empty (an image that was not asked for).
template <typename T>
py::object to_image(std::vector<T>&& v, int h, int w, int c = 1) {
  if (v.empty()) return py::none();
  return as_image(to_numpy(std::move(v)), h, w, c);
}

/// (4,4) or (N,4,4) float64 -> rigid poses. Checks finiteness, a [0 0 0 1] last row and an
/// orthonormal right-handed rotation (tolerance 1e-6), naming `arg` and the index in errors.
std::vector<Pose> to_poses(const py::handle& obj, const char* arg);

/// Single (4,4) pose.
Pose to_pose(const py::handle& obj, const char* arg);

/// Rigid pose -> (4,4) float64 array.
py::array pose_to_numpy(const Pose& X);

/// Rigid poses -> (N,4,4) float64 array.
py::array poses_to_numpy(const std::vector<Pose>& poses);

}  // namespace mgn::py_conv
