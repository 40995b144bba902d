#pragma once
// Small helpers shared by the mgn-cli subcommands: argument parsing, JSON strings, atomic writes.
#include <string>

namespace mgn {
class Mesh;
}

namespace mgn_cli {

/// `text` as an integer; InvalidArgument naming `what` (e.g. "mgn-cli pj: --seed") otherwise.
int to_int(const std::string& what, const std::string& text);
/// `text` as a number; InvalidArgument naming `what` otherwise.
double to_double(const std::string& what, const std::string& text);
/// A value read as a number that must be a whole number (e.g. a YAML count).
int whole_number(const std::string& what, double value);
bool ends_with(const std::string& s, const std::string& suffix);
/// A JSON string literal (quoted, escaped).
std::string json_string(const std::string& s);
/// Writes `text` to `path` through a temporary file and a rename, so readers never see a partial
/// file. IoError naming `who` and the path on failure.
void write_atomically(const std::string& path, const std::string& text, const std::string& who);
/// Prints a warning to stderr (naming `who` and `path`) when the largest extent of `mesh` is
/// implausible for a picked part: above 1 m (a file in millimetres read as metres?) or below
/// 1 mm (a file in metres scaled down twice?). Returns true when it warned.
bool warn_implausible_size(const std::string& who, const std::string& path, const mgn::Mesh& mesh);

}  // namespace mgn_cli
