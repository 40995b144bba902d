#pragma once
// A minimal reader of flat YAML files as written by mgn.hardware (yaml.safe_dump of a dataclass):
// one `key: value` per line at the top level, where a value is a number, a plain or quoted string,
// null / ~, a flow list `[a, b, c]`, or a block list (following lines `- item`). Comments (#) and
// blank lines are ignored. Nested mappings, anchors and multi-line strings are rejected with an
// error naming the file and line. Shared by the mgn-cli subcommands that read hardware files.
#include <map>
#include <string>
#include <vector>

namespace mgn_cli {

class FlatYaml {
 public:
  /// Parses text; `source` names it in errors (e.g. the file path). Throws mgn::InvalidArgument.
  static FlatYaml parse(const std::string& text, const std::string& source);
  /// Reads and parses a file. Throws mgn::IoError if it cannot be read.
  static FlatYaml load(const std::string& path);

  bool has(const std::string& key) const { return values_.count(key) != 0; }
  /// True if the key is present with value null / ~ / empty.
  bool is_null(const std::string& key) const;
  std::vector<std::string> keys() const;
  /// Throws mgn::InvalidArgument naming the first key not in `known` and listing the valid keys.
  void require_known(const std::vector<std::string>& known) const;

  /// Typed access; each throws mgn::InvalidArgument naming the source, line and key when the key
  /// is missing or the value has the wrong type.
  double number(const std::string& key) const;
  std::string string(const std::string& key) const;
  std::vector<double> numbers(const std::string& key) const;  ///< a list of numbers

  /// Like the above, but return `fallback` when the key is absent.
  double number_or(const std::string& key, double fallback) const;
  std::string string_or(const std::string& key, const std::string& fallback) const;

 private:
  struct Value {
    bool is_list = false;
    bool is_null = false;
    std::string scalar;
    std::vector<std::string> items;
    int line = 0;
  };
  const Value& get(const std::string& key) const;
  std::string where(const std::string& key) const;

  std::string source_;
  std::map<std::string, Value> values_;
};

}  // namespace mgn_cli
