#include "cli.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace softhd::cli {

Args::Args(std::vector<std::string> tokens)
    : tokens_(std::move(tokens)), used_(tokens_.size(), false) {}

bool Args::flag(const std::string& name) {
  bool found = false;
  for (size_t i = 0; i < tokens_.size(); ++i) {
    if (!used_[i] && tokens_[i] == name) used_[i] = found = true;
  }
  return found;
}

std::vector<std::string> Args::values(const std::string& name) {
  std::vector<std::string> out;
  const std::string prefix = name + "=";
  for (size_t i = 0; i < tokens_.size(); ++i) {
    if (used_[i]) continue;
    if (tokens_[i] == name) {
      if (i + 1 >= tokens_.size()) throw UsageError(name + " needs a value");
      used_[i] = used_[i + 1] = true;
      out.push_back(tokens_[i + 1]);
      ++i;
    } else if (tokens_[i].compare(0, prefix.size(), prefix) == 0) {
      used_[i] = true;
      out.push_back(tokens_[i].substr(prefix.size()));
    }
  }
  return out;
}

std::optional<std::string> Args::value(const std::string& name) {
  std::vector<std::string> all = values(name);
  if (all.empty()) return std::nullopt;
  if (all.size() > 1) throw UsageError(name + " given more than once");
  return all.front();
}

double parse_number(const std::string& text, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw UsageError(what + ": expected a finite number, got '" + text + "'");
  }
  // A subnormal (1e-320) is a double like any other: the option's own validation (e.g.
  // HausdorffParams::validate for --eps) judges it and names the bound. Only a nonzero
  // literal read as 0 is refused here.
  if (errno == ERANGE && v == 0.0) {
    throw UsageError(what + ": " + text +
                     " underflows to 0 in double precision (the smallest double is 4.9e-324)");
  }
  if ((errno == ERANGE && std::fabs(v) >= 1.0) || !std::isfinite(v)) {
    throw UsageError(what + ": " + text + " is not a finite double (at most 1.8e308 in magnitude)");
  }
  return v;
}

double Args::number(const std::string& name, double fallback) {
  const std::optional<std::string> v = value(name);
  return v ? parse_number(*v, name) : fallback;
}

long Args::integer(const std::string& name, long fallback) {
  const std::optional<std::string> v = value(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  const long n = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || end != v->c_str() + v->size() || errno == ERANGE) {
    throw UsageError(name + ": expected an integer, got '" + *v + "'");
  }
  return n;
}

long Args::integer(const std::string& name, long fallback, long lo, long hi) {
  const std::optional<std::string> v = value(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  const long n = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || end != v->c_str() + v->size() || errno == ERANGE || n < lo || n > hi) {
    throw UsageError(name + ": expected an integer from " + std::to_string(lo) + " to " +
                     std::to_string(hi) + ", got '" + *v + "'");
  }
  return n;
}

void Args::retired(const std::string& old_name, const std::string& new_name) const {
  for (size_t i = 0; i < tokens_.size(); ++i)
    if (!used_[i] && (tokens_[i] == old_name || tokens_[i].rfind(old_name + "=", 0) == 0))
      throw UsageError(old_name + " is now " + new_name);
}

std::vector<std::string> Args::finish() {
  std::vector<std::string> positional;
  for (size_t i = 0; i < tokens_.size(); ++i) {
    if (used_[i]) continue;
    if (tokens_[i].size() > 1 && tokens_[i][0] == '-' && tokens_[i] != "-") {
      throw UsageError("unknown option '" + tokens_[i] + "' (see --help)");
    }
    positional.push_back(tokens_[i]);
  }
  return positional;
}

}  // namespace softhd::cli
