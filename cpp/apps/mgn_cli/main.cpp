// mgn-cli: the standalone command-line tool of mgn for industrial integration.
// Uses only the public headers. Output is JSON on stdout; errors are one line on stderr with a
// non-zero exit code, as `mgn`'s: 2 = no or an unknown command, 1 = any error (a bad option or
// value, an unreadable file, a failed operation).
#include <mgn/mgn.hpp>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "cmd_pj.hpp"
#include "cmd_seal.hpp"

namespace {

using mgn_cli::json_string;

const char* kUsage =
    "usage: mgn-cli [--help] [--version] <command> [options]\n"
    "\n"
    "commands:\n"
    "  info MESH [--scale S] [--density D]\n"
    "      Load MESH (OBJ, STL, PLY, GLB/GLTF, DAE) and print its validation report and mass\n"
    "      properties as JSON. S multiplies coordinates (0.001 for millimetres; default 1),\n"
    "      D is the density in kg/m^3 (default 1000). Units in the output: m, m^2, m^3, kg, kg "
    "m^2.\n"
    "  version\n"
    "      Print the versions of mgn and of the libraries it was built with, as JSON.\n";

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(10) << v;
  return os.str();
}

template <typename Vec>
std::string json_vec(const Vec& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_number(v[i]);
  return s + "]";
}

double parse_number(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') {
    throw mgn::InvalidArgument("mgn-cli: " + flag + " expects a number, got '" + text + "'");
  }
  return v;
}

int cmd_version() {
  std::cout << "{";
  bool first = true;
  for (const auto& [name, version] : mgn::build_info()) {
    std::cout << (first ? "" : ", ") << json_string(name) << ": " << json_string(version);
    first = false;
  }
  std::cout << "}\n";
  return 0;
}

int cmd_info(const std::vector<std::string>& args) {
  std::string path;
  mgn::LoadOptions load;
  mgn::MassOptions mass;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--scale" || a == "--density") {
      if (i + 1 >= args.size()) throw mgn::InvalidArgument("mgn-cli info: " + a + " needs a value");
      const double v = parse_number(a, args[++i]);
      (a == "--scale" ? load.scale : mass.density) = v;
    } else if (!a.empty() && a[0] == '-') {
      throw mgn::InvalidArgument("mgn-cli info: unknown option '" + a + "'");
    } else if (path.empty()) {
      path = a;
    } else {
      mgn::throw_error<mgn::InvalidArgument>("mgn-cli info: expected one MESH, got '", path,
                                             "' and '", a, "'");
    }
  }
  if (path.empty()) throw mgn::InvalidArgument("mgn-cli info: missing MESH argument");
  const mgn::Mesh mesh = mgn::load_mesh(path, load);
  mgn_cli::warn_implausible_size("mgn-cli info", path, mesh);
  const mgn::MeshReport r = mesh.validate();
  const mgn::MassProperties m = mgn::compute_mass_properties(mesh, mass);
  const auto b = mesh.bounds();
  std::cout << "{\n"
            << "  \"path\": " << json_string(path) << ",\n"
            << "  \"name\": " << json_string(mesh.name()) << ",\n"
            << "  \"num_vertices\": " << r.num_vertices << ",\n"
            << "  \"num_faces\": " << r.num_faces << ",\n"
            << "  \"num_materials\": " << mesh.materials().size() << ",\n"
            << "  \"has_uvs\": " << (mesh.uvs().rows() > 0 ? "true" : "false") << ",\n"
            << "  \"bounds_min\": " << json_vec(b.row(0)) << ",\n"
            << "  \"bounds_max\": " << json_vec(b.row(1)) << ",\n"
            << "  \"validation\": {\"is_watertight\": " << (r.is_watertight ? "true" : "false")
            << ", \"is_winding_consistent\": " << (r.is_winding_consistent ? "true" : "false")
            << ", \"is_outward\": " << (r.is_outward ? "true" : "false")
            << ", \"num_boundary_edges\": " << r.num_boundary_edges
            << ", \"num_nonmanifold_edges\": " << r.num_nonmanifold_edges
            << ", \"num_misoriented_edges\": " << r.num_misoriented_edges
            << ", \"num_components\": " << r.num_components
            << ", \"num_split_edges\": " << r.num_split_edges
            << ", \"num_split_vertices\": " << r.num_split_vertices
            << ", \"area\": " << json_number(r.area)
            << ", \"signed_volume\": " << json_number(r.signed_volume) << "},\n"
            << "  \"mass_properties\": {\"density\": " << json_number(mass.density)
            << ", \"volume\": " << json_number(m.volume) << ", \"mass\": " << json_number(m.mass)
            << ", \"center_of_mass\": " << json_vec(m.center_of_mass) << ", \"inertia\": ["
            << json_vec(m.inertia.row(0)) << ", " << json_vec(m.inertia.row(1)) << ", "
            << json_vec(m.inertia.row(2)) << "], \"is_exact\": " << (m.is_exact ? "true" : "false")
            << "}\n"
            << "}\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::cout << kUsage << mgn_cli::kPjUsage << mgn_cli::kSealUsage;
    return args.empty() ? 2 : 0;
  }
  try {
    const std::string cmd = args[0];
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    for (const auto& a : rest) {
      if (a == "--help" || a == "-h") {
        std::cout << kUsage << mgn_cli::kPjUsage << mgn_cli::kSealUsage;
        return 0;
      }
    }
    if (cmd == "--version" || cmd == "version") return cmd_version();
    if (cmd == "info") return cmd_info(rest);
    if (cmd == "pj") return mgn_cli::cmd_pj(rest);
    if (cmd == "seal") return mgn_cli::cmd_seal(rest);
    std::cerr << "mgn-cli: unknown command '" << cmd << "' (see mgn-cli --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "mgn-cli: error: " << e.what() << "\n";
    return 1;
  }
}
