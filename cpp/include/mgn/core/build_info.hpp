#pragma once
/// @file build_info.hpp  Versions of mgn and of the libraries it was built against.

#include <string>
#include <utility>
#include <vector>

namespace mgn {

/// mgn version, e.g. "0.1.0".
std::string version();

/// (library, version) pairs for every third-party library linked into mgn.
std::vector<std::pair<std::string, std::string>> build_info();

}  // namespace mgn
