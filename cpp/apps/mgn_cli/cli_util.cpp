#include "cli_util.hpp"

#include <mgn/core/error.hpp>
#include <mgn/geometry/mesh.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace mgn_cli {

int to_int(const std::string& what, const std::string& text) {
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0') {
    throw mgn::InvalidArgument(what + " expects an integer, got '" + text + "'");
  }
  return static_cast<int>(v);
}

double to_double(const std::string& what, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') {
    throw mgn::InvalidArgument(what + " expects a number, got '" + text + "'");
  }
  return v;
}

int whole_number(const std::string& what, double value) {
  if (!std::isfinite(value) || value != std::floor(value) || std::abs(value) > 1e9) {
    throw mgn::InvalidArgument(what + ": expected a whole number, got " + std::to_string(value));
  }
  return static_cast<int>(value);
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string json_string(const std::string& s) {
  std::ostringstream os;
  os << '"';
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        os << "\\\"";
        break;
      case '\\':
        os << "\\\\";
        break;
      case '\n':
        os << "\\n";
        break;
      case '\t':
        os << "\\t";
        break;
      default:
        if (c < 0x20) {
          os << "\\u" << std::hex << std::setw(4) << std::setfill('0') << static_cast<int>(c)
             << std::dec;
        } else {
          os << c;
        }
    }
  }
  os << '"';
  return os.str();
}

void write_atomically(const std::string& path, const std::string& text, const std::string& who) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw mgn::IoError(who + ": cannot write '" + tmp + "'");
    out << text;
    if (!out.flush()) {
      out.close();
      std::remove(tmp.c_str());
      throw mgn::IoError(who + ": cannot write '" + tmp + "' (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw mgn::IoError(who + ": cannot rename '" + tmp + "' to '" + path + "'");
  }
}

bool warn_implausible_size(const std::string& who, const std::string& path, const mgn::Mesh& mesh) {
  if (mesh.num_vertices() == 0) return false;
  const auto b = mesh.bounds();
  const double extent = (b.row(1) - b.row(0)).maxCoeff();
  std::ostringstream msg;
  msg << std::setprecision(3);
  if (extent > 1.0) {
    msg << who << ": warning: '" << path << "' is " << extent
        << " m across, too large for a part in a tote; if the file is in millimetres, "
           "pass --scale 0.001";
  } else if (extent < 1e-3) {
    msg << who << ": warning: '" << path << "' is " << extent * 1e3
        << " mm across, too small for a picked part; check --scale (the file's unit)";
  } else {
    return false;
  }
  std::cerr << msg.str() << "\n";
  return true;
}

}  // namespace mgn_cli
