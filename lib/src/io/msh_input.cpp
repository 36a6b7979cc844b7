// The MSH reader's input cursor: ASCII tokens, binary values, messages (msh_internal.hpp).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <system_error>

#include "msh_internal.hpp"
#include "softhd/error.hpp"

namespace softhd::io::msh_detail {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

// A token for messages: at most 40 characters, quoted.
std::string shown(std::string_view token) {
  if (token.size() > 40) return "'" + std::string(token.substr(0, 40)) + "...'";
  return "'" + std::string(token) + "'";
}

}  // namespace

Input::Input(const std::string& bytes, const std::string& source)
    : bytes_(bytes), source_(source) {}

void Input::fail_at(const Mark& at, const std::string& what) const {
  if (!binary_) throw FileError(source_ + ":" + std::to_string(at.line) + ": " + what);
  const std::string where = section_.empty() ? "at byte " : section_ + " at byte ";
  throw FileError(source_ + ": " + where + std::to_string(at.pos) + ": " + what);
}

void Input::skip_space() {
  while (pos_ < bytes_.size() && is_space(bytes_[pos_])) {
    if (bytes_[pos_] == '\n') ++line_;
    ++pos_;
  }
}

bool Input::at_end() {
  skip_space();
  mark_ = {pos_, line_};
  return pos_ == bytes_.size();
}

std::string_view Input::token(const char* what) {
  if (at_end()) fail(std::string("unexpected end of file, expected ") + what);
  const std::size_t start = pos_;
  while (pos_ < bytes_.size() && !is_space(bytes_[pos_])) ++pos_;
  return std::string_view(bytes_).substr(start, pos_ - start);
}

void Input::expect(std::string_view word) {
  const std::string w(word);
  const std::string_view got = token(w.c_str());
  if (got != word) fail("expected " + w + ", got " + shown(got));
}

bool Input::skip_prefix(std::string_view prefix) {
  if (std::string_view(bytes_).substr(pos_, prefix.size()) != prefix) return false;
  pos_ += prefix.size();
  return true;
}

void Input::end_line(bool only_blanks) {
  while (pos_ < bytes_.size() && bytes_[pos_] != '\n') {
    if (only_blanks && !is_space(bytes_[pos_])) {
      mark_ = {pos_, line_};
      fail("unexpected text at the end of the line");
    }
    ++pos_;
  }
  if (pos_ == bytes_.size()) {
    mark_ = {pos_, line_};
    fail("unexpected end of file");
  }
  ++pos_;
  ++line_;
}

std::string Input::quoted(const char* what) {
  if (at_end()) fail(std::string("unexpected end of file, expected ") + what);
  if (bytes_[pos_] != '"') fail(std::string("expected ") + what + " in double quotes");
  const std::size_t start = ++pos_;
  while (pos_ < bytes_.size() && bytes_[pos_] != '"' && bytes_[pos_] != '\n') ++pos_;
  if (pos_ == bytes_.size() || bytes_[pos_] != '"')
    fail(std::string(what) + " has no closing quote");
  ++pos_;
  return bytes_.substr(start, pos_ - 1 - start);
}

void Input::skip_section(const std::string& name) {
  const std::string end = "$End" + name.substr(1);
  std::size_t at = pos_;
  while (true) {
    at = bytes_.find(end, at);
    if (at == std::string::npos) fail("no " + end + " for " + name);
    // the end marker starts a line and is followed by whitespace or the end
    const bool starts = at == 0 || bytes_[at - 1] == '\n' || bytes_[at - 1] == '\r';
    const std::size_t after = at + end.size();
    if (starts && (after == bytes_.size() || is_space(bytes_[after]))) break;
    at = after;
  }
  line_ +=
      static_cast<std::size_t>(std::count(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                          bytes_.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  pos_ = at + end.size();
}

long long Input::ascii_integer(const char* what, long long lo, long long hi) {
  const std::string_view t = token(what);
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec == std::errc::result_out_of_range)
    fail(std::string(what) + " " + shown(t) + " is too large");
  if (ec != std::errc() || ptr != t.data() + t.size()) {
    fail(std::string("expected ") + what + " (an integer), got " + shown(t));
  }
  if (value < lo || value > hi) {
    fail(std::string(what) + " " + std::to_string(value) + " is out of range [" +
         std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return value;
}

double Input::ascii_real(const char* what) {
  const std::string_view t = token(what);
  const char* first = t.data();
  const char* last = first + t.size();
  if (first != last && *first == '+') ++first;
  double value = 0;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range)
    fail(std::string(what) + " " + shown(t) + " is out of range");
  if (ec != std::errc() || ptr != last || first == last) {
    fail(std::string("expected ") + what + " (a number), got " + shown(t));
  }
  return value;
}

const char* Input::take(std::size_t n, const char* what) {
  mark_ = {pos_, line_};
  if (remaining() < n) {
    fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
         std::to_string(remaining()) + " left");
  }
  const char* p = bytes_.data() + pos_;
  pos_ += n;
  return p;
}

std::uint64_t Input::binary_size(const char* what) {
  std::uint64_t v = 0;
  std::memcpy(&v, take(sizeof v, what), sizeof v);
  return v;
}

std::size_t Input::count(const char* what, std::size_t min_bytes) {
  constexpr long long kMax = std::numeric_limits<long long>::max();
  if (!binary_) return ascii_count(what, min_bytes);
  const std::uint64_t n = binary_size(what);
  if (n > static_cast<std::uint64_t>(kMax)) fail(std::string(what) + " is negative or too large");
  return check_count(n, what, min_bytes);
}

std::size_t Input::ascii_count(const char* what, std::size_t min_bytes) {
  constexpr long long kMax = std::numeric_limits<long long>::max();
  const long long v = ascii_integer(what, std::numeric_limits<long long>::min(), kMax);
  if (v < 0) fail(std::string(what) + " " + std::to_string(v) + " is negative");
  return check_count(static_cast<std::uint64_t>(v), what, min_bytes);
}

std::size_t Input::check_count(std::uint64_t n, const char* what, std::size_t min_bytes) const {
  if (n > remaining() / std::max<std::size_t>(min_bytes, 1)) {
    fail(std::string(what) + " " + std::to_string(n) + " exceeds what the " +
         std::to_string(remaining()) + " bytes left can hold");
  }
  return static_cast<std::size_t>(n);
}

std::int64_t Input::size_value(const char* what) {
  constexpr long long kMax = std::numeric_limits<std::int64_t>::max();
  if (!binary_) return ascii_integer(what, 0, kMax);
  const std::uint64_t v = binary_size(what);
  if (v > static_cast<std::uint64_t>(kMax)) fail(std::string(what) + " is too large");
  return static_cast<std::int64_t>(v);
}

std::int64_t Input::size_tag(const char* what) {
  constexpr long long kMax = std::numeric_limits<std::int64_t>::max();
  if (!binary_) return ascii_integer(what, 1, kMax);
  const std::uint64_t v = binary_size(what);
  if (v < 1 || v > static_cast<std::uint64_t>(kMax)) {
    fail(std::string(what) + " " + std::to_string(v) + " is out of range [1, " +
         std::to_string(kMax) + "]");
  }
  return static_cast<std::int64_t>(v);
}

int Input::int_value(const char* what, long long lo, long long hi) {
  if (!binary_) return static_cast<int>(ascii_integer(what, lo, hi));
  std::int32_t v = 0;
  std::memcpy(&v, take(sizeof v, what), sizeof v);
  if (v < lo || v > hi) {
    fail(std::string(what) + " " + std::to_string(v) + " is out of range [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]");
  }
  return v;
}

double Input::real(const char* what) {
  double v = 0;
  if (binary_) {
    std::memcpy(&v, take(sizeof v, what), sizeof v);
  } else {
    v = ascii_real(what);
  }
  if (!std::isfinite(v)) fail(std::string("non-finite ") + what);
  return v;
}

}  // namespace softhd::io::msh_detail
