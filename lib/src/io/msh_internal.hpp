#pragma once
// Internal to the MSH reader (msh.cpp, msh_input.cpp, msh_v2.cpp, msh_v4.cpp): the input
// cursor (ASCII tokens and binary values, with the error messages of msh.hpp) and the
// state shared by the sections' parsers.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "softhd/io/msh.hpp"

namespace softhd::io::msh_detail {

/// A place in the input, for messages: byte offset, line, section.
struct Mark {
  std::size_t pos = 0;
  std::size_t line = 1;
};

/// A cursor over the file's bytes. ASCII numbers are whitespace-separated tokens; binary
/// values (MSH 4.1 binary, little-endian) are read in place. Every failure throws
/// FileError "<file>:<line>: <what>" (ASCII) or "<file>: $Section at byte N: <what>".
class Input {
 public:
  Input(const std::string& bytes, const std::string& source);

  bool binary() const { return binary_; }
  void set_binary(bool binary) { binary_ = binary; }
  /// The section being read ("$Nodes"), for binary messages.
  void set_section(std::string section) { section_ = std::move(section); }
  const std::string& section() const { return section_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }
  Mark mark() const { return mark_; }

  /// Skips whitespace; true if nothing is left.
  bool at_end();
  /// The next whitespace-separated token; fails at the end of the input.
  std::string_view token(const char* what);
  /// Fails unless the next token is `word`.
  void expect(std::string_view word);
  /// Skips `prefix` if the input goes on with it (no whitespace skipped); true if it did.
  bool skip_prefix(std::string_view prefix);
  /// Skips blanks to the end of the current line and past its newline (before binary
  /// data, and to skip the rest of a line); fails on other text if `only_blanks`.
  void end_line(bool only_blanks);
  /// A double-quoted string (may hold blanks; one line).
  std::string quoted(const char* what);
  /// Skips to just past "$End<name>" (an unknown section).
  void skip_section(const std::string& name);

  /// ASCII numbers.
  long long ascii_integer(const char* what, long long lo, long long hi);
  double ascii_real(const char* what);
  /// A count of items each taking at least `min_bytes` bytes: ASCII token, or binary
  /// size_t if binary(). Fails if negative or more than the remaining bytes can hold.
  std::size_t count(const char* what, std::size_t min_bytes);
  /// The same, always ASCII (the text headers of binary files).
  std::size_t ascii_count(const char* what, std::size_t min_bytes);
  /// ASCII token or binary size_t, in [0, INT64_MAX], unchecked otherwise (min/max tags).
  std::int64_t size_value(const char* what);
  /// Binary only: skips `n` bytes (fails if fewer are left).
  void skip_bytes(std::size_t n, const char* what) { take(n, what); }
  /// ASCII token or binary size_t: a tag in [1, INT64_MAX].
  std::int64_t size_tag(const char* what);
  /// ASCII token or binary int (4 bytes), in [lo, hi].
  int int_value(const char* what, long long lo, long long hi);
  /// ASCII token or binary double; fails unless finite.
  double real(const char* what);

  [[noreturn]] void fail(const std::string& what) const { fail_at(mark_, what); }
  [[noreturn]] void fail_at(const Mark& at, const std::string& what) const;
  const std::string& source() const { return source_; }

 private:
  void skip_space();
  const char* take(std::size_t n, const char* what);  // binary bytes
  std::uint64_t binary_size(const char* what);
  std::size_t check_count(std::uint64_t n, const char* what, std::size_t min_bytes) const;

  const std::string& bytes_;
  std::string source_;
  std::string section_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
  Mark mark_;
  bool binary_ = false;
};

/// An element block of a type the reader does not keep, for the top-dimension check.
struct SkippedBlock {
  int gmsh_type = 0;
  int dim = 0;
  std::size_t count = 0;
  Mark at;
};

/// The state of one parse.
struct Parse {
  Parse(Input& input, MshFile& file) : in(input), out(file) {}
  Input& in;
  MshFile& out;
  bool have_entities = false;
  bool have_nodes = false;
  bool have_elements = false;
  /// Physical tags of each (dim, entity tag) of $Entities (MSH 4.1).
  std::map<std::pair<int, int>, std::vector<int>> entities;
  std::vector<SkippedBlock> skipped;
  /// All element tags, sorted (built for $ElementData).
  std::vector<std::int64_t> element_tags;
};

/// Node count and dimension of a Gmsh type the reader does not keep (prisms, pyramids,
/// hex20, higher orders); {0, -1} if unknown.
std::pair<int, int> other_element_type(int gmsh_type);
/// Sorts the nodes by tag into p.out (compacted), refusing duplicates (reported at `at`).
void set_nodes(Parse& p, std::vector<std::int64_t>& tags, std::vector<double>& xyz, const Mark& at);
/// The compacted index of node `tag`; fails (at the current token) if undefined.
int node_index(const Parse& p, std::int64_t tag);

/// Skips a UTF-8 byte order mark, checks the $MeshFormat token and reads the section.
void read_format(Parse& p);

void read_entities_v4(Parse& p);
void read_nodes_v4(Parse& p);
void read_elements_v4(Parse& p);
void read_nodes_v2(Parse& p);
void read_elements_v2(Parse& p);

}  // namespace softhd::io::msh_detail
