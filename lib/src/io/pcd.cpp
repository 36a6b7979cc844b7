// PCD point clouds (PCL's format, version 0.7 and earlier): ascii, binary and binary_compressed
// (LZF) data (docs/formulation.md §6.1).

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "cloud_io_internal.hpp"
#include "softhd/io/cloud_io.hpp"

namespace softhd {

using namespace detail;

namespace {

/// The names of a field holding the points' volumes, in order of preference.
const char* const kVolumeNames[] = {"volume", "weight", "area"};

struct PcdField {
  std::string name;
  char type = 'F';         // F float, I signed, U unsigned
  int size = 4;            // bytes of one value
  int count = 1;           // values per point
  std::size_t offset = 0;  // of its first byte in a binary record
  int role = -1;           // 0..2: x, y, z; 3: volume; −1: skipped
};

enum class PcdData { ascii, binary, compressed };

struct PcdHeader {
  std::vector<PcdField> fields;
  std::size_t record = 0;  // bytes per point
  unsigned long long points = 0;
  PcdData data = PcdData::ascii;
  bool has_volume = false;
  std::size_t body = 0;       // offset of the first data byte
  std::size_t body_line = 0;  // line of the first ascii data line
};

unsigned long long parse_count(const std::string& path, std::size_t line, std::string_view t,
                               const char* what) {
  unsigned long long v = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || ptr != t.data() + t.size())
    fail_at(path, line, std::string("invalid ") + what + " " + quoted(t));
  return v;
}

// Checks the FIELDS, SIZE, TYPE and COUNT lines agree and gives each field its offset and role.
void finish_fields(const std::string& path, std::size_t line, PcdHeader& h) {
  h.record = 0;
  for (PcdField& f : h.fields) {
    const bool ok = f.type == 'F' ? (f.size == 4 || f.size == 8)
                                  : (f.size == 1 || f.size == 2 || f.size == 4 || f.size == 8);
    if (!ok)
      fail_at(path, line,
              "field " + quoted(f.name) + ": type " + std::string(1, f.type) +
                  " cannot have size " + std::to_string(f.size));
    f.offset = h.record;
    h.record += static_cast<std::size_t>(f.size) * static_cast<std::size_t>(f.count);
    for (int r = 0; r < 3; ++r)
      if (f.name == std::string(1, char('x' + r))) f.role = r;
  }
  for (const char* v : kVolumeNames) {
    for (PcdField& f : h.fields)
      if (!h.has_volume && f.name == v) f.role = 3, h.has_volume = true;
    if (h.has_volume) break;
  }
  bool seen[4] = {false, false, false, false};
  for (const PcdField& f : h.fields) {
    if (f.role < 0) continue;
    if (seen[f.role]) fail_at(path, line, "duplicate field " + quoted(f.name));
    if (f.count != 1) fail_at(path, line, "field " + quoted(f.name) + " must have COUNT 1");
    seen[f.role] = true;
  }
  if (!seen[0] || !seen[1] || !seen[2]) fail(path, "the FIELDS line needs x, y and z");
}

// One header line's values into the fields (`what` is FIELDS, SIZE, TYPE or COUNT).
void parse_field_line(const std::string& path, std::size_t line, const std::string& what,
                      const std::vector<std::string_view>& t, PcdHeader& h) {
  if (what == "FIELDS") {
    if (t.size() < 2) fail_at(path, line, "FIELDS names no field");
    h.fields.assign(t.size() - 1, PcdField());
    for (std::size_t k = 1; k < t.size(); ++k) h.fields[k - 1].name = std::string(t[k]);
    return;
  }
  if (h.fields.empty()) fail_at(path, line, what + " before FIELDS");
  if (t.size() != h.fields.size() + 1)
    fail_at(path, line,
            what + " has " + std::to_string(t.size() - 1) + " values for " +
                std::to_string(h.fields.size()) + " fields");
  for (std::size_t k = 1; k < t.size(); ++k) {
    PcdField& f = h.fields[k - 1];
    if (what == "TYPE") {
      if (t[k].size() != 1 || (t[k][0] != 'F' && t[k][0] != 'I' && t[k][0] != 'U'))
        fail_at(path, line, "unknown TYPE " + quoted(t[k]) + " (expected F, I or U)");
      f.type = t[k][0];
      continue;
    }
    const unsigned long long v = parse_count(path, line, t[k], what == "SIZE" ? "SIZE" : "COUNT");
    if (v < 1 || v > 1000000) fail_at(path, line, what + " out of range: " + quoted(t[k]));
    (what == "SIZE" ? f.size : f.count) = static_cast<int>(v);
  }
}

PcdHeader parse_pcd_header(const std::string& path, const std::string& data,
                           std::vector<std::string>* notes) {
  PcdHeader h;
  unsigned long long width = 0, height = 1;
  bool have_points = false, have_width = false, have_size = false, have_type = false;
  std::size_t pos = 0;
  for (std::size_t line = 1;; ++line) {
    if (pos >= data.size()) fail(path, line == 1 ? "empty file" : "missing DATA line");
    std::size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) eol = data.size();
    const std::vector<std::string_view> t =
        split_blanks(std::string_view(data).substr(pos, eol - pos));
    pos = std::min(eol + 1, data.size());
    if (t.empty() || t[0][0] == '#') continue;
    const std::string key(t[0]);
    auto one = [&](const char* what) {
      if (t.size() != 2) fail_at(path, line, std::string("expected '") + what + " <value>'");
      return parse_count(path, line, t[1], what);
    };
    if (key == "VERSION") continue;
    if (key == "FIELDS" || key == "SIZE" || key == "TYPE" || key == "COUNT") {
      parse_field_line(path, line, key, t, h);
      have_size = have_size || key == "SIZE";
      have_type = have_type || key == "TYPE";
    } else if (key == "WIDTH") {
      width = one("WIDTH"), have_width = true;
    } else if (key == "HEIGHT") {
      height = one("HEIGHT");
    } else if (key == "POINTS") {
      h.points = one("POINTS"), have_points = true;
    } else if (key == "VIEWPOINT") {
      if (t.size() != 8) fail_at(path, line, "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
      static const double kIdentity[] = {0, 0, 0, 1, 0, 0, 0};
      for (int k = 0; k < 7; ++k) {
        double v = 0.0;
        if (parse_double(t[static_cast<std::size_t>(k) + 1], v) != nullptr)
          fail_at(path, line, "VIEWPOINT: expected a number, got " + quoted(t[k + 1]));
        if (notes != nullptr && v != kIdentity[k]) {
          notes->push_back(path + ": the VIEWPOINT is not the identity and is ignored");
          break;
        }
      }
    } else if (key == "DATA") {
      if (t.size() != 2) fail_at(path, line, "expected 'DATA ascii|binary|binary_compressed'");
      if (t[1] == "ascii")
        h.data = PcdData::ascii;
      else if (t[1] == "binary")
        h.data = PcdData::binary;
      else if (t[1] == "binary_compressed")
        h.data = PcdData::compressed;
      else
        fail_at(path, line,
                "unknown DATA " + quoted(t[1]) + " (expected ascii, binary or binary_compressed)");
      if (h.fields.empty() || !have_size || !have_type)
        fail_at(path, line, "DATA before the FIELDS, SIZE and TYPE lines");
      if (!have_width) fail_at(path, line, "DATA before the WIDTH line");
      if (height != 0 && width > ULLONG_MAX / height)
        fail_at(path, line,
                "WIDTH x HEIGHT = " + std::to_string(width) + " x " + std::to_string(height) +
                    " is too large");
      if (!have_points) h.points = width * height;
      if (width * height != h.points)
        fail_at(path, line,
                "WIDTH x HEIGHT = " + std::to_string(width * height) +
                    " but POINTS = " + std::to_string(h.points));
      finish_fields(path, line, h);
      h.body = pos;
      h.body_line = line + 1;
      return h;
    } else {
      fail_at(path, line, "unexpected header line starting with " + quoted(t[0]));
    }
  }
}

// An integer of `size` bytes at p (of type I8, I16, I32 or I64), converted to double
// (exactly; 64-bit integers: rounded).
template <class I8, class I16, class I32, class I64>
double load_pcd_integer(int size, const char* p) {
  switch (size) {
    case 1:
      return load_le<I8>(p);
    case 2:
      return load_le<I16>(p);
    case 4:
      return load_le<I32>(p);
    default:
      return static_cast<double>(load_le<I64>(p));
  }
}

// A value of field f at p, converted exactly to double (64-bit integers: rounded).
double load_pcd(const PcdField& f, const char* p) {
  if (f.type == 'F') return f.size == 4 ? load_le<float>(p) : load_le<double>(p);
  if (f.type == 'I')
    return load_pcd_integer<std::int8_t, std::int16_t, std::int32_t, std::int64_t>(f.size, p);
  return load_pcd_integer<std::uint8_t, std::uint16_t, std::uint32_t, std::uint64_t>(f.size, p);
}

// Appends point `i`'s x y z [V] (row[4], in role order) to `values`, or drops it if x, y and z
// are all NaN (PCL's mark of an invalid point). Returns false if dropped.
// `line` > 0: the ascii line of the point, else `i` its index in binary data (for messages).
bool add_point(const std::string& path, std::size_t line, std::size_t i, const double* row,
               bool has_volume, std::vector<double>& values) {
  if (std::isnan(row[0]) && std::isnan(row[1]) && std::isnan(row[2])) return false;
  for (int r = 0; r < (has_volume ? 4 : 3); ++r) {
    if (const char* problem = check_value(row[r], r == 3)) {
      const std::string what =
          std::string(problem) + " (" + (r == 3 ? "volume" : std::string(1, char('x' + r))) + ")";
      if (line > 0) fail_at(path, line, what);
      fail(path, "point " + std::to_string(i) + ": " + what);
    }
    values.push_back(row[r]);
  }
  return true;
}

}  // namespace

namespace detail {

// LZF (liblzf's format, as PCL writes it): a control byte c < 32 starts a run of c + 1
// literal bytes; otherwise a back reference of length (c >> 5) + 2 (c >> 5 = 7: plus the next
// byte) to the offset ((c & 31) << 8 | next byte) + 1 behind the output's end.
std::string lzf_decompress(const std::string& path, const char* in, std::size_t in_size,
                           std::size_t out_size) {
  std::string out;
  out.reserve(out_size);
  const char* const end = in + in_size;
  auto corrupt = [&](const char* what) {
    fail(path, std::string("corrupt binary_compressed data: ") + what);
  };
  while (in < end) {
    const unsigned c = static_cast<unsigned char>(*in++);
    if (c < 32) {
      const std::size_t run = c + 1;
      if (static_cast<std::size_t>(end - in) < run) corrupt("a literal run past the end");
      if (out.size() + run > out_size) corrupt("more data than the header's size");
      out.append(in, run);
      in += run;
      continue;
    }
    std::size_t length = c >> 5;
    if (length == 7) {
      if (in == end) corrupt("a reference past the end");
      length += static_cast<unsigned char>(*in++);
    }
    length += 2;
    if (in == end) corrupt("a reference past the end");
    const std::size_t back = ((c & 31u) << 8 | static_cast<unsigned char>(*in++)) + 1;
    if (back > out.size()) corrupt("a reference before the start");
    if (out.size() + length > out_size) corrupt("more data than the header's size");
    for (std::size_t k = 0; k < length; ++k) out.push_back(out[out.size() - back]);
  }
  if (out.size() != out_size) corrupt("less data than the header's size");
  return out;
}

}  // namespace detail

namespace {

void read_pcd_ascii(const std::string& path, const std::string& data, const PcdHeader& h,
                    std::vector<double>& values, unsigned long long& dropped) {
  std::size_t tokens = 0;
  for (const PcdField& f : h.fields) tokens += static_cast<std::size_t>(f.count);
  std::size_t pos = h.body, line = h.body_line;
  unsigned long long read = 0;
  std::vector<double> fieldvals(tokens);
  for (; pos < data.size(); ++line) {
    std::size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) eol = data.size();
    const std::vector<std::string_view> t =
        split_blanks(std::string_view(data).substr(pos, eol - pos));
    pos = eol + 1;
    if (t.empty()) continue;
    if (read == h.points)
      fail_at(path, line, "more points than POINTS = " + std::to_string(h.points));
    if (t.size() != tokens)
      fail_at(path, line,
              "expected " + std::to_string(tokens) + " values, got " + std::to_string(t.size()));
    double row[4] = {1.0, 1.0, 1.0, 1.0};
    std::size_t k = 0;
    for (const PcdField& f : h.fields) {
      for (int c = 0; c < f.count; ++c, ++k) {
        if (f.role < 0) continue;
        if (const char* problem = parse_double(t[k], row[f.role]))
          fail_at(path, line, std::string(problem) + " (" + f.name + "), got " + quoted(t[k]));
      }
    }
    if (!add_point(path, line, 0, row, h.has_volume, values)) ++dropped;
    ++read;
  }
  if (read != h.points)
    fail(path, "the file has " + std::to_string(read) + " points, POINTS says " +
                   std::to_string(h.points));
}

// Binary data: `points` records of h.record bytes (interleaved), or with `columns` the
// fields one after the other (binary_compressed's layout once decompressed).
void read_pcd_records(const std::string& path, const char* p, const PcdHeader& h, bool columns,
                      std::vector<double>& values, unsigned long long& dropped) {
  const std::size_t n = static_cast<std::size_t>(h.points);
  for (std::size_t i = 0; i < n; ++i) {
    double row[4] = {1.0, 1.0, 1.0, 1.0};
    for (const PcdField& f : h.fields) {
      if (f.role < 0) continue;
      const std::size_t at =
          columns ? f.offset * n + i * static_cast<std::size_t>(f.size) : i * h.record + f.offset;
      row[f.role] = load_pcd(f, p + at);
    }
    if (!add_point(path, 0, i, row, h.has_volume, values)) ++dropped;
  }
}

}  // namespace

PointCloud parse_pcd_cloud(const std::string& data, const std::string& path,
                           std::vector<std::string>* notes) {
  const PcdHeader h = parse_pcd_header(path, data, notes);
  std::vector<double> values;
  unsigned long long dropped = 0;
  const std::size_t rest = data.size() - h.body;
  if (h.data == PcdData::ascii) {
    read_pcd_ascii(path, data, h, values, dropped);
  } else if (h.data == PcdData::binary) {
    if (h.record == 0 || h.points > rest / h.record)
      fail(path, "truncated binary data: " + std::to_string(rest) + " bytes for " +
                     std::to_string(h.points) + " points of " + std::to_string(h.record) +
                     " bytes");
    values.reserve(static_cast<std::size_t>(h.points) * 4);
    read_pcd_records(path, data.data() + h.body, h, false, values, dropped);
  } else {
    if (rest < 8) fail(path, "truncated binary_compressed data (no sizes)");
    const std::uint32_t packed = load_le<std::uint32_t>(data.data() + h.body);
    const std::uint32_t unpacked = load_le<std::uint32_t>(data.data() + h.body + 4);
    if (packed > rest - 8) fail(path, "truncated binary_compressed data");
    if (h.record == 0 || unpacked / h.record != h.points || unpacked % h.record != 0)
      fail(path, "binary_compressed: " + std::to_string(unpacked) + " bytes do not hold " +
                     std::to_string(h.points) + " points of " + std::to_string(h.record) +
                     " bytes");
    // LZF expands at most 264 bytes per 2 input bytes: a larger claim is corrupt (and is
    // not allocated).
    if (unpacked > 132.0 * packed + 64)
      fail(path, "binary_compressed: the uncompressed size is impossible for the data");
    const std::string raw = lzf_decompress(path, data.data() + h.body + 8, packed, unpacked);
    values.reserve(static_cast<std::size_t>(h.points) * 4);
    read_pcd_records(path, raw.data(), h, true, values, dropped);
  }
  if (notes != nullptr) {
    std::string skipped;
    for (const PcdField& f : h.fields)
      if (f.role < 0 && f.name != "_") skipped += (skipped.empty() ? "" : ", ") + f.name;
    if (!skipped.empty()) notes->push_back(path + ": fields " + skipped + " ignored");
    if (dropped > 0)
      notes->push_back(path + ": " + std::to_string(dropped) +
                       " invalid points (x, y and z NaN) dropped");
  }
  return make_cloud(path, values, h.has_volume ? 4 : 3, 3, h.has_volume);
}

PointCloud read_pcd_cloud(const std::string& path, std::vector<std::string>* notes) {
  return parse_pcd_cloud(read_file(path), path, notes);
}

}  // namespace softhd
