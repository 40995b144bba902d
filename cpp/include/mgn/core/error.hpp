#pragma once
/// @file error.hpp  The one exception hierarchy of mgn.
///
/// Every error thrown by the library derives from mgn::Error. Messages name the function, the
/// value received and the value expected. The Python bindings map each class to a Python
/// exception that also derives from the matching builtin:
///   InvalidArgument -> mgn.InvalidArgumentError (ValueError)
///   IoError         -> mgn.IoError (OSError)
///   Unsupported     -> mgn.UnsupportedError (ValueError)
///   BackendError    -> mgn.BackendError (RuntimeError)

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace mgn {

/// Base of all mgn errors.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
/// An argument has a wrong value, shape or range (bad mesh, NaN pose, negative density, ...).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};
/// A file could not be read or written (missing, unreadable, corrupt).
class IoError : public Error {
 public:
  using Error::Error;
};
/// A valid request that this build or format does not support.
class Unsupported : public Error {
 public:
  using Error::Error;
};
/// A third-party backend (Embree, FCL, assimp, ...) reported a failure.
class BackendError : public Error {
 public:
  using Error::Error;
};

namespace detail {
template <typename... Args>
std::string concat(Args&&... args) {
  std::ostringstream os;
  (os << ... << std::forward<Args>(args));
  return os.str();
}
}  // namespace detail

/// Throws E with the streamed concatenation of args, e.g.
/// `throw_error<InvalidArgument>("Mesh: density must be > 0, got ", d)`.
template <typename E, typename... Args>
[[noreturn]] void throw_error(Args&&... args) {
  throw E(detail::concat(std::forward<Args>(args)...));
}

}  // namespace mgn
