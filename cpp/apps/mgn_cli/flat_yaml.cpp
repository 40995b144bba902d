#include "flat_yaml.hpp"

#include <mgn/core/error.hpp>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace mgn_cli {

namespace {

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

/// Removes a comment (# at the start or after whitespace, outside quotes).
std::string strip_comment(const std::string& line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '#' && (i == 0 || std::isspace(static_cast<unsigned char>(line[i - 1])))) {
      return line.substr(0, i);
    }
  }
  return line;
}

bool is_null_text(const std::string& s) { return s.empty() || s == "null" || s == "~"; }

/// A scalar without its quotes ('' escapes ' in single quotes; \" and \\ in double quotes).
std::string unquote(const std::string& s, const std::string& where) {
  if (s.size() >= 2 && s.front() == '\'' && s.back() == '\'') {
    std::string out;
    for (std::size_t i = 1; i + 1 < s.size(); ++i) {
      out += s[i];
      if (s[i] == '\'' && s[i + 1] == '\'') ++i;
    }
    return out;
  }
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') {
    std::string out;
    for (std::size_t i = 1; i + 1 < s.size(); ++i) {
      if (s[i] == '\\' && i + 2 < s.size()) ++i;
      out += s[i];
    }
    return out;
  }
  if (!s.empty() &&
      (s.front() == '\'' || s.front() == '"' || s.front() == '{' || s.front() == '&' ||
       s.front() == '*' || s.front() == '|' || s.front() == '>')) {
    mgn::throw_error<mgn::InvalidArgument>(where, ": unsupported YAML value '", s,
                                           "' (expected a number, a string or a list)");
  }
  return s;
}

}  // namespace

FlatYaml FlatYaml::parse(const std::string& text, const std::string& source) {
  FlatYaml y;
  y.source_ = source;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  std::string open_key;  // key whose block list is being read
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string where = source + ":" + std::to_string(line_no);
    if (!raw.empty() && raw.back() == '\r') raw.pop_back();
    const std::string line = strip_comment(raw);
    const std::string t = trim(line);
    if (t.empty() || t == "---" || t == "...") continue;
    const bool indented = std::isspace(static_cast<unsigned char>(line[0]));
    if (t[0] == '-' && (t.size() == 1 || t[1] == ' ')) {
      if (open_key.empty()) {
        mgn::throw_error<mgn::InvalidArgument>(where, ": list item outside a 'key:' block");
      }
      Value& v = y.values_[open_key];
      v.is_list = true;
      v.is_null = false;
      v.items.push_back(unquote(trim(t.substr(1)), where));
      continue;
    }
    if (indented) {
      mgn::throw_error<mgn::InvalidArgument>(
          where, ": nested mappings are not supported (expected flat 'key: value' lines)");
    }
    open_key.clear();
    const std::size_t colon = t.find(": ");
    const bool ends_with_colon = t.back() == ':';
    if (colon == std::string::npos && !ends_with_colon) {
      mgn::throw_error<mgn::InvalidArgument>(where, ": expected 'key: value', got '", t, "'");
    }
    const std::string key = unquote(
        trim(t.substr(0, ends_with_colon && colon == std::string::npos ? t.size() - 1 : colon)),
        where);
    const std::string rest = colon == std::string::npos ? std::string() : trim(t.substr(colon + 2));
    if (key.empty()) mgn::throw_error<mgn::InvalidArgument>(where, ": empty key");
    if (y.values_.count(key)) {
      mgn::throw_error<mgn::InvalidArgument>(where, ": duplicate key '", key, "'");
    }
    Value v;
    v.line = line_no;
    if (is_null_text(rest)) {
      v.is_null = true;
      open_key = key;  // a block list may follow
    } else if (rest.front() == '[') {
      if (rest.back() != ']') {
        mgn::throw_error<mgn::InvalidArgument>(where, ": unterminated list '", rest, "'");
      }
      v.is_list = true;
      const std::string body = trim(rest.substr(1, rest.size() - 2));
      if (!body.empty()) {
        std::stringstream items(body);
        std::string item;
        while (std::getline(items, item, ',')) v.items.push_back(unquote(trim(item), where));
      }
    } else {
      v.scalar = unquote(rest, where);
    }
    y.values_[key] = v;
  }
  return y;
}

FlatYaml FlatYaml::load(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    mgn::throw_error<mgn::IoError>("YAML file '", path, "' is a folder; expected a YAML file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) mgn::throw_error<mgn::IoError>("cannot read YAML file '", path, "'");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  // Text only: no NUL byte and no control characters other than tab, CR and LF.
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u == 0 || (u < 0x20 && c != '\t' && c != '\n' && c != '\r') || u == 0x7f) {
      mgn::throw_error<mgn::InvalidArgument>("YAML file '", path,
                                             "' is a binary file; expected YAML text");
    }
  }
  return parse(text, path);
}

bool FlatYaml::is_null(const std::string& key) const {
  auto it = values_.find(key);
  return it != values_.end() && it->second.is_null;
}

std::vector<std::string> FlatYaml::keys() const {
  std::vector<std::string> out;
  for (const auto& kv : values_) out.push_back(kv.first);
  return out;
}

void FlatYaml::require_known(const std::vector<std::string>& known) const {
  for (const auto& kv : values_) {
    bool ok = false;
    for (const auto& k : known) ok = ok || k == kv.first;
    if (!ok) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      mgn::throw_error<mgn::InvalidArgument>(where(kv.first), ": unknown key '", kv.first,
                                             "'; valid keys are ", list);
    }
  }
}

std::string FlatYaml::where(const std::string& key) const {
  auto it = values_.find(key);
  return source_ + (it == values_.end() ? "" : ":" + std::to_string(it->second.line));
}

const FlatYaml::Value& FlatYaml::get(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) {
    mgn::throw_error<mgn::InvalidArgument>(source_, ": missing key '", key, "'");
  }
  return it->second;
}

namespace {
bool to_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0';
}
}  // namespace

double FlatYaml::number(const std::string& key) const {
  const Value& v = get(key);
  double out = 0.0;
  if (v.is_list || v.is_null || !to_double(v.scalar, out)) {
    mgn::throw_error<mgn::InvalidArgument>(where(key), ": key '", key,
                                           "': expected a number, got '",
                                           v.is_list ? "[list]" : v.scalar, "'");
  }
  return out;
}

std::string FlatYaml::string(const std::string& key) const {
  const Value& v = get(key);
  if (v.is_list || v.is_null) {
    mgn::throw_error<mgn::InvalidArgument>(where(key), ": key '", key, "': expected a string");
  }
  return v.scalar;
}

std::vector<double> FlatYaml::numbers(const std::string& key) const {
  const Value& v = get(key);
  if (!v.is_list) {
    mgn::throw_error<mgn::InvalidArgument>(where(key), ": key '", key,
                                           "': expected a list of numbers, got '", v.scalar, "'");
  }
  std::vector<double> out;
  for (const std::string& item : v.items) {
    double d = 0.0;
    if (!to_double(item, d)) {
      mgn::throw_error<mgn::InvalidArgument>(where(key), ": key '", key,
                                             "': expected numbers, got '", item, "'");
    }
    out.push_back(d);
  }
  return out;
}

double FlatYaml::number_or(const std::string& key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

std::string FlatYaml::string_or(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

}  // namespace mgn_cli
