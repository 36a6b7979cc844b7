#include "softhd/io/cloud_io.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "cloud_io_internal.hpp"
#include "softhd/error.hpp"
#include "softhd/io/atomic_file.hpp"

namespace softhd {
namespace detail {

// ---------------------------------------------------------------------------
// Files, messages, numbers

std::string read_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  std::string data;
  char buffer[1 << 16];
  std::size_t got = 0;
  errno = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, f)) > 0) data.append(buffer, got);
  const int err = errno;
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) {
    throw FileError("cannot read '" + path + "': " + std::strerror(err != 0 ? err : EIO));
  }
  return data;
}

void write_file(const std::string& path, const std::string& data) {
  write_file_atomically(path, data);
}

[[noreturn]] void fail_at(const std::string& path, std::size_t line, const std::string& what) {
  throw FileError(path + ":" + std::to_string(line) + ": " + what);
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw FileError(path + ": " + what);
}

void check_dim(int dim) {
  if (dim != 0 && dim != 2 && dim != 3) {
    throw InvalidArgument("read_cloud: dim must be 0 (auto), 2 or 3, got " + std::to_string(dim));
  }
}

// Parses the whole of `token` as a double. Returns nullptr on success, else
// what is wrong with it.
const char* parse_double(std::string_view token, double& value) {
  const char* first = token.data();
  const char* last = first + token.size();
  if (first != last && *first == '+') {
    ++first;
    if (first == last || *first == '+' || *first == '-') return "expected a number";
  }
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) return "number out of the range of a double";
  if (ec != std::errc() || ptr != last) return "expected a number";
  return nullptr;
}

// What is wrong with `value` as a coordinate (volume = false) or a volume, or nullptr.
const char* check_value(double value, bool volume) {
  if (!std::isfinite(value)) return volume ? "non-finite volume" : "non-finite coordinate";
  if (volume && !(value > 0.0)) return "volume must be > 0";
  return nullptr;
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

// Appends the shortest decimal form that reads back to exactly `value`.
void append_number(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

// Builds the cloud from row-major `values` with `cols` numbers per point, of
// which the first `dim` are coordinates and the next (if `has_volume`) the volume.
PointCloud make_cloud(const std::string& path, const std::vector<double>& values, int cols, int dim,
                      bool has_volume) {
  if (values.empty()) fail(path, "no points in the file");
  const Eigen::Index n = static_cast<Eigen::Index>(values.size()) / cols;
  Eigen::MatrixXd points(n, dim);
  Eigen::VectorXd volumes = Eigen::VectorXd::Ones(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double* row = values.data() + i * cols;
    for (int k = 0; k < dim; ++k) points(i, k) = row[k];
    if (has_volume) volumes[i] = row[dim];
  }
  try {
    return PointCloud(std::move(points), std::move(volumes));
  } catch (const InvalidArgument& e) {  // e.g. the total volume overflows
    fail(path, e.what());
  }
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string_view> split_blanks(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

}  // namespace detail

using namespace detail;

namespace {

// ---------------------------------------------------------------------------
// Text

// Splits one line (without its comment and newline) into fields separated by
// blanks and/or single commas. Stores up to 10 fields, returns how many there are.
int split_fields(const std::string& path, std::size_t line, const char* p, const char* stop,
                 std::string_view* fields) {
  int n = 0;
  bool after_comma = false;
  while (true) {
    while (p < stop && is_blank(*p)) ++p;
    if (p == stop || *p == ',') {
      if (p == stop && !after_comma) return n;
      if (p == stop || after_comma || n == 0) fail_at(path, line, "empty field (stray ',')");
      after_comma = true;
      ++p;
      continue;
    }
    const char* start = p;
    while (p < stop && !is_blank(*p) && *p != ',') ++p;
    if (n < 10) fields[n] = std::string_view(start, static_cast<std::size_t>(p - start));
    ++n;
    after_comma = false;
  }
}

}  // namespace

PointCloud read_text_cloud(const std::string& path, int dim, std::vector<std::string>* notes) {
  check_dim(dim);
  return parse_text_cloud(read_file(path), path, dim, notes);
}

namespace {
// The columns x y z [V] of a 3D line with 3 or 6 more (colours and/or normals, ignored):
// 6 or 9 columns -> 3, 7 or 10 -> 4; else 0.
int read_columns_3d(int n) { return n == 6 || n == 9 ? 3 : n == 7 || n == 10 ? 4 : 0; }
}  // namespace

PointCloud parse_text_cloud(const std::string& data, const std::string& path, int dim,
                            std::vector<std::string>* notes) {
  check_dim(dim);
  const char* p = data.data();
  const char* const end = p + data.size();
  if (data.compare(0, 3, "\xEF\xBB\xBF") == 0) p += 3;  // UTF-8 byte order mark

  std::vector<double> values;  // row-major, `used` numbers per point
  int cols = 0, used = 0;
  int point_dim = 0;
  bool has_volume = false;
  std::size_t cols_line = 0;
  for (std::size_t line = 1; p < end; ++line) {
    const char* eol =
        static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    if (eol == nullptr) eol = end;
    const char* stop =
        static_cast<const char*>(std::memchr(p, '#', static_cast<std::size_t>(eol - p)));
    if (stop == nullptr) stop = eol;
    std::string_view fields[10];
    const int n = split_fields(path, line, p, stop, fields);
    p = eol + (eol < end ? 1 : 0);
    if (n == 0) continue;

    if (cols == 0) {
      const bool extra = dim != 2 && read_columns_3d(n) > 0;
      const bool ok = extra || (dim == 0 ? (n >= 2 && n <= 4) : (n == dim || n == dim + 1));
      if (!ok) {
        const char* expected =
            dim == 0   ? "2, 3 or 4 columns (x y [z] [V]; in 3D 3 or 6 more may follow)"
            : dim == 2 ? "2 or 3 columns (x y [V]) for dim=2"
                       : "3 or 4 columns (x y z [V]; 3 or 6 more may follow) for dim=3";
        fail_at(path, line, std::string("expected ") + expected + ", got " + std::to_string(n));
      }
      cols = n;
      used = extra ? read_columns_3d(n) : n;
      cols_line = line;
      point_dim = extra ? 3 : dim != 0 ? dim : std::min(n, 3);
      has_volume = used > point_dim;
      if (extra && notes != nullptr)
        notes->push_back(path + ": columns " + std::to_string(used + 1) + " to " +
                         std::to_string(n) + " (colours or normals) ignored");
    } else if (n != cols) {
      fail_at(path, line,
              "mixed dimensions: line " + std::to_string(line) + " has " + std::to_string(n) +
                  " columns, line " + std::to_string(cols_line) + " had " + std::to_string(cols));
    }
    for (int k = 0; k < used; ++k) {
      double value = 0.0;
      const char* problem = parse_double(fields[k], value);
      if (problem == nullptr) problem = check_value(value, k == point_dim);
      if (problem != nullptr)
        fail_at(path, line, std::string(problem) + ", got " + quoted(fields[k]));
      values.push_back(value);
    }
  }
  return make_cloud(path, values, used, point_dim, has_volume);
}

void write_text_cloud(const std::string& path, const PointCloud& cloud, bool with_volumes) {
  const int d = cloud.dim();
  std::string out = "# softhd point cloud: " + std::to_string(cloud.size()) + " points, columns: ";
  out += d == 3 ? "x y z" : "x y";
  out += with_volumes ? (d == 2 ? " V (read with dim=2)\n" : " V\n") : "\n";
  out.reserve(out.size() + static_cast<std::size_t>(cloud.size()) * 25 * (d + 1));
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < d; ++k) {
      if (k > 0) out += ' ';
      append_number(out, cloud.points()(i, k));
    }
    if (with_volumes) {
      out += ' ';
      append_number(out, cloud.volumes()[i]);
    }
    out += '\n';
  }
  write_file(path, out);
}

// ---------------------------------------------------------------------------
// PLY

namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parse_ply_type(std::string_view name, PlyType& type) {
  struct Entry {
    const char* name;
    PlyType type;
  };
  static const Entry kTypes[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const Entry& e : kTypes) {
    if (name == e.name) {
      type = e.type;
      return true;
    }
  }
  return false;
}

std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

template <class T>
void store_le(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  std::reverse(bytes, bytes + sizeof(T));
#endif
  out.append(bytes, sizeof(T));
}

double load_ply(PlyType t, const char* p) {
  switch (t) {
    case PlyType::kInt8:
      return load_le<std::int8_t>(p);
    case PlyType::kUint8:
      return load_le<std::uint8_t>(p);
    case PlyType::kInt16:
      return load_le<std::int16_t>(p);
    case PlyType::kUint16:
      return load_le<std::uint16_t>(p);
    case PlyType::kInt32:
      return load_le<std::int32_t>(p);
    case PlyType::kUint32:
      return load_le<std::uint32_t>(p);
    case PlyType::kFloat32:
      return load_le<float>(p);
    case PlyType::kFloat64:
      return load_le<double>(p);
  }
  return 0.0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat64;  // of the value, or of the list items
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
  int role = -1;  // vertex only: 0..2 = x, y, z; 3 = volume; -1 = skipped
};

struct PlyElement {
  std::string name;
  unsigned long long count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  bool binary = false;
  std::vector<PlyElement> elements;
  int vertex = -1;  // index into elements
  bool has_z = false;
  bool has_volume = false;
  std::size_t body = 0;       // offset of the first byte after the header
  std::size_t body_line = 0;  // line number of the first body line
};

PlyHeader parse_ply_header(const std::string& path, const std::string& data) {
  PlyHeader h;
  bool have_format = false;
  std::size_t pos = 0;
  for (std::size_t line = 1;; ++line) {
    const std::size_t eol = data.find('\n', pos);
    if (eol == std::string::npos && pos >= data.size()) {
      fail(path, line == 1 ? "empty file (expected 'ply')" : "missing 'end_header'");
    }
    const std::size_t next = eol == std::string::npos ? data.size() : eol + 1;
    const std::vector<std::string_view> t = split_blanks(
        std::string_view(data).substr(pos, (eol == std::string::npos ? data.size() : eol) - pos));
    pos = next;
    auto bad = [&](const std::string& what) { fail_at(path, line, what); };
    if (line == 1) {
      if (t.size() != 1 || t[0] != "ply") bad("not a PLY file (the first line must be 'ply')");
      continue;
    }
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "end_header") {
      h.body = pos;
      h.body_line = line + 1;
      break;
    }
    if (t[0] == "format") {
      if (t.size() != 3) bad("expected 'format <ascii|binary_little_endian> 1.0'");
      if (t[1] == "binary_big_endian") {
        bad("big-endian binary PLY is not supported (use ascii or binary_little_endian)");
      }
      if (t[1] != "ascii" && t[1] != "binary_little_endian") {
        bad("unknown PLY format " + quoted(t[1]));
      }
      if (t[2] != "1.0") bad("unsupported PLY version " + quoted(t[2]) + " (expected 1.0)");
      h.binary = t[1] == "binary_little_endian";
      have_format = true;
    } else if (t[0] == "element") {
      if (t.size() != 3) bad("expected 'element <name> <count>'");
      PlyElement e;
      e.name = std::string(t[1]);
      const auto [ptr, ec] = std::from_chars(t[2].data(), t[2].data() + t[2].size(), e.count);
      if (ec != std::errc() || ptr != t[2].data() + t[2].size()) {
        bad("invalid element count " + quoted(t[2]));
      }
      if (e.name == "vertex") {
        if (h.vertex >= 0) bad("a second 'vertex' element");
        h.vertex = static_cast<int>(h.elements.size());
      }
      h.elements.push_back(std::move(e));
    } else if (t[0] == "property") {
      if (h.elements.empty()) bad("'property' before any 'element'");
      PlyElement& e = h.elements.back();
      PlyProperty prop;
      prop.is_list = t.size() >= 2 && t[1] == "list";
      if (t.size() != (prop.is_list ? 5u : 3u)) {
        bad("expected 'property <type> <name>' or 'property list <count type> <type> <name>'");
      }
      const std::string_view type_name = t[prop.is_list ? 3 : 1];
      if (!parse_ply_type(type_name, prop.type)) bad("unknown property type " + quoted(type_name));
      if (prop.is_list) {
        if (!parse_ply_type(t[2], prop.count_type)) bad("unknown property type " + quoted(t[2]));
        if (prop.count_type == PlyType::kFloat32 || prop.count_type == PlyType::kFloat64) {
          bad("list count type must be an integer type, got " + quoted(t[2]));
        }
      }
      prop.name = std::string(t.back());
      if (h.vertex == static_cast<int>(h.elements.size()) - 1) {
        static const char* const kRoles[] = {"x", "y", "z", "volume"};
        for (int r = 0; r < 4; ++r) {
          if (prop.name != kRoles[r]) continue;
          if (prop.is_list) bad("vertex property " + quoted(prop.name) + " must not be a list");
          for (const PlyProperty& other : e.properties) {
            if (other.role == r) bad("duplicate vertex property " + quoted(prop.name));
          }
          prop.role = r;
        }
      }
      e.properties.push_back(std::move(prop));
    } else {
      bad("unexpected header line starting with " + quoted(t[0]));
    }
  }
  if (!have_format) fail(path, "the header has no 'format' line");
  if (h.vertex < 0) fail(path, "no 'vertex' element");
  bool has_role[4] = {false, false, false, false};
  for (const PlyProperty& prop : h.elements[static_cast<std::size_t>(h.vertex)].properties) {
    if (prop.role >= 0) has_role[prop.role] = true;
  }
  if (!has_role[0] || !has_role[1]) fail(path, "the vertex element needs properties x and y");
  h.has_z = has_role[2];
  h.has_volume = has_role[3];
  return h;
}

// The column of `role` in a row of x, y, [z,] volume.
int column_of(int role, bool has_z) { return role == 3 ? (has_z ? 3 : 2) : role; }

void read_ply_binary(const std::string& path, const std::string& data, const PlyHeader& h,
                     std::vector<double>& values) {
  const int cols = h.has_z ? 4 : 3;
  const char* p = data.data() + h.body;
  const char* const end = data.data() + data.size();
  for (std::size_t ei = 0; ei < h.elements.size(); ++ei) {
    const PlyElement& e = h.elements[ei];
    const bool is_vertex = static_cast<int>(ei) == h.vertex;
    auto truncated = [&](unsigned long long i) {
      fail(path, "truncated binary data in element " + quoted(e.name) + " (item " +
                     std::to_string(i) + " of " + std::to_string(e.count) + ")");
    };
    std::size_t min_bytes = 0;  // per item
    for (const PlyProperty& prop : e.properties) {
      min_bytes += ply_size(prop.is_list ? prop.count_type : prop.type);
    }
    if (min_bytes > 0 && e.count > static_cast<unsigned long long>(end - p) / min_bytes) {
      truncated(static_cast<unsigned long long>(end - p) / min_bytes);
    }
    if (is_vertex) values.assign(static_cast<std::size_t>(e.count) * cols, 1.0);
    if (e.properties.empty()) continue;  // nothing to read, however large the count
    for (unsigned long long i = 0; i < e.count; ++i) {
      for (const PlyProperty& prop : e.properties) {
        if (prop.is_list) {
          const std::size_t count_size = ply_size(prop.count_type);
          if (static_cast<std::size_t>(end - p) < count_size) truncated(i);
          const double count = load_ply(prop.count_type, p);
          p += count_size;
          if (count < 0) fail(path, "negative list length in element " + quoted(e.name));
          const double bytes = count * static_cast<double>(ply_size(prop.type));
          if (bytes > static_cast<double>(end - p)) truncated(i);
          p += static_cast<std::size_t>(bytes);
          continue;
        }
        const std::size_t size = ply_size(prop.type);
        if (static_cast<std::size_t>(end - p) < size) truncated(i);
        if (is_vertex && prop.role >= 0) {
          const double value = load_ply(prop.type, p);
          if (const char* problem = check_value(value, prop.role == 3)) {
            fail(path, "vertex " + std::to_string(i) + ": " + problem + " (" + prop.name + ")");
          }
          values[static_cast<std::size_t>(i) * cols + column_of(prop.role, h.has_z)] = value;
        }
        p += size;
      }
    }
  }
  // A line break some tools append is tolerated; more data means the header's counts are
  // too small (a third vertex under "element vertex 2" would otherwise be dropped silently).
  const bool line_break =
      end - p <= 2 && std::all_of(p, end, [](char c) { return c == '\n' || c == '\r'; });
  if (!line_break) {
    fail(path, std::to_string(end - p) +
                   " bytes of data after the last element (the header's counts are too small)");
  }
}

// Reads whitespace-separated tokens; `line` is that of the last token read.
struct TokenReader {
  const char* p;
  const char* end;
  std::size_t next_line;  // of the position p
  std::size_t line = 0;

  bool next(std::string_view& token) {
    while (p < end && (is_blank(*p) || *p == '\n')) {
      if (*p == '\n') ++next_line;
      ++p;
    }
    if (p == end) return false;
    line = next_line;
    const char* start = p;
    while (p < end && !is_blank(*p) && *p != '\n') ++p;
    token = std::string_view(start, static_cast<std::size_t>(p - start));
    return true;
  }
};

void read_ply_ascii(const std::string& path, const std::string& data, const PlyHeader& h,
                    std::vector<double>& values) {
  const int cols = h.has_z ? 4 : 3;
  TokenReader in{data.data() + h.body, data.data() + data.size(), h.body_line};
  in.line = h.body_line - 1;  // the end_header line
  std::string_view token;
  for (std::size_t ei = 0; ei < h.elements.size(); ++ei) {
    const PlyElement& e = h.elements[ei];
    const bool is_vertex = static_cast<int>(ei) == h.vertex;
    if (is_vertex) {
      // Every vertex takes at least two bytes per property; do not trust the count further.
      const std::size_t at_most =
          static_cast<std::size_t>(in.end - in.p) / (2 * e.properties.size()) + 1;
      values.reserve(std::min<std::size_t>(static_cast<std::size_t>(e.count), at_most) * cols);
    }
    if (e.properties.empty()) continue;  // nothing to read, however large the count
    for (unsigned long long i = 0; i < e.count; ++i) {
      if (is_vertex) values.resize(values.size() + cols, 1.0);
      for (const PlyProperty& prop : e.properties) {
        auto number = [&]() {
          if (!in.next(token)) {
            fail_at(path, in.line,
                    "unexpected end of file in element " + quoted(e.name) + " (item " +
                        std::to_string(i) + " of " + std::to_string(e.count) + ")");
          }
          double value = 0.0;
          if (const char* problem = parse_double(token, value)) {
            fail_at(path, in.line, std::string(problem) + ", got " + quoted(token));
          }
          return value;
        };
        if (prop.is_list) {
          const double count = number();
          if (!(count >= 0) || count != std::floor(count)) {
            fail_at(path, in.line, "invalid list length " + quoted(token));
          }
          for (double j = 0; j < count; ++j) number();
          continue;
        }
        const double value = number();
        if (is_vertex && prop.role >= 0) {
          if (const char* problem = check_value(value, prop.role == 3)) {
            fail_at(path, in.line, std::string(problem) + ", got " + quoted(token));
          }
          values[values.size() - cols + column_of(prop.role, h.has_z)] = value;
        }
      }
    }
  }
  if (in.next(token)) {
    fail_at(path, in.line, "unexpected data after the last element: " + quoted(token));
  }
}

}  // namespace

PointCloud read_ply_cloud(const std::string& path, std::vector<std::string>* notes) {
  return parse_ply_cloud(read_file(path), path, notes);
}

PointCloud parse_ply_cloud(const std::string& data, const std::string& path,
                           std::vector<std::string>* notes) {
  const PlyHeader h = parse_ply_header(path, data);
  if (notes != nullptr) {
    std::string skipped;
    for (const PlyProperty& prop : h.elements[static_cast<std::size_t>(h.vertex)].properties)
      if (prop.role < 0) skipped += (skipped.empty() ? "" : ", ") + prop.name;
    if (!skipped.empty()) notes->push_back(path + ": vertex properties " + skipped + " ignored");
  }
  std::vector<double> values;  // rows of x, y, [z,] volume
  if (h.binary) {
    read_ply_binary(path, data, h, values);
  } else {
    read_ply_ascii(path, data, h, values);
  }
  return make_cloud(path, values, h.has_z ? 4 : 3, h.has_z ? 3 : 2, h.has_volume);
}

void write_ply_cloud(const std::string& path, const PointCloud& cloud, bool binary) {
  const int d = cloud.dim();
  std::string out = "ply\nformat ";
  out += binary ? "binary_little_endian" : "ascii";
  out += " 1.0\ncomment written by softhd\nelement vertex " + std::to_string(cloud.size()) +
         "\nproperty double x\nproperty double y\n";
  if (d == 3) out += "property double z\n";
  out += "property double volume\nend_header\n";
  out.reserve(out.size() + static_cast<std::size_t>(cloud.size()) * 25 * (d + 1));
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k <= d; ++k) {
      const double value = k < d ? cloud.points()(i, k) : cloud.volumes()[i];
      if (binary) {
        store_le(out, value);
      } else {
        if (k > 0) out += ' ';
        append_number(out, value);
      }
    }
    if (!binary) out += '\n';
  }
  write_file(path, out);
}

namespace {
// Whether `path` ends in `ext` (".ply", ".pcd"), in any case.
bool has_extension(const std::string& path, const char* ext) {
  std::string tail = path.size() >= 4 ? path.substr(path.size() - 4) : std::string();
  std::transform(tail.begin(), tail.end(), tail.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return tail == ext;
}
bool is_ply_name(const std::string& path) { return has_extension(path, ".ply"); }
}  // namespace

void write_cloud(const std::string& path, const PointCloud& cloud) {
  if (is_ply_name(path))
    write_ply_cloud(path, cloud);
  else
    write_text_cloud(path, cloud);
}

PointCloud read_cloud(const std::string& path, int dim, std::vector<std::string>* notes) {
  check_dim(dim);
  const bool pcd = has_extension(path, ".pcd");
  if (!pcd && !is_ply_name(path)) return read_text_cloud(path, dim, notes);
  PointCloud cloud = pcd ? read_pcd_cloud(path, notes) : read_ply_cloud(path, notes);
  if (dim != 0 && cloud.dim() != dim) {
    fail(path, "the file holds a " + std::to_string(cloud.dim()) +
                   "D cloud but dim=" + std::to_string(dim) + " was requested");
  }
  return cloud;
}

}  // namespace softhd
