#pragma once
// Helpers shared by the cloud readers (cloud_io.cpp: text and PLY; pcd.cpp: PCD). Internal.

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "softhd/point_cloud.hpp"

namespace softhd::detail {

/// The whole file; FileError if it cannot be opened or read.
std::string read_file(const std::string& path);
void write_file(const std::string& path, const std::string& data);
/// FileError "path:line: what" / "path: what".
[[noreturn]] void fail_at(const std::string& path, std::size_t line, const std::string& what);
[[noreturn]] void fail(const std::string& path, const std::string& what);
/// InvalidArgument unless dim is 0, 2 or 3.
void check_dim(int dim);
/// Parses the whole of `token` as a double; nullptr on success, else what is wrong.
const char* parse_double(std::string_view token, double& value);
/// What is wrong with `value` as a coordinate (volume = false) or a volume, or nullptr.
const char* check_value(double value, bool volume);
std::string quoted(std::string_view s);
/// The cloud of row-major `values`, `cols` per point: `dim` coordinates, then the volume if
/// `has_volume`. FileError naming `path` if there are none or the cloud is invalid.
PointCloud make_cloud(const std::string& path, const std::vector<double>& values, int cols, int dim,
                      bool has_volume);
bool is_blank(char c);
/// The blank-separated tokens of one line.
std::vector<std::string_view> split_blanks(std::string_view line);

/// LZF-decompresses `in_size` bytes at `in` into exactly `out_size` bytes; FileError naming
/// `path` if the data are corrupt or do not give out_size bytes (pcd.cpp).
std::string lzf_decompress(const std::string& path, const char* in, std::size_t in_size,
                           std::size_t out_size);

/// A little-endian value of type T at p (any alignment).
template <class T>
T load_le(const char* p) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  std::reverse(bytes, bytes + sizeof(T));
#endif
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

}  // namespace softhd::detail
