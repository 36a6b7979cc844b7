#include "softhd/io/pose_io.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "softhd/error.hpp"
#include "softhd/io/atomic_file.hpp"

namespace softhd {

namespace {

/// The fields of one line: separated by whitespace and/or single commas.
std::vector<std::string> fields(std::string line) {
  for (char& c : line)
    if (c == ',') c = ' ';
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string f; in >> f;) out.push_back(f);
  return out;
}

double number(const std::string& text, const std::string& where) {
  size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size()) throw FileError(where + ": expected a number, got '" + text + "'");
  if (!std::isfinite(v)) throw FileError(where + ": '" + text + "' is not finite");
  return v;
}

}  // namespace

Eigen::Matrix4d parse_pose_matrix(const std::string& text, const std::string& name) {
  Eigen::Matrix4d m;
  int rows = 0, line_no = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    const std::vector<std::string> f = fields(line);
    if (f.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_no);
    if (f.size() != 4)
      throw FileError(where + ": expected 4 numbers, got " + std::to_string(f.size()));
    if (rows < 4)
      for (int c = 0; c < 4; ++c) m(rows, c) = number(f[static_cast<size_t>(c)], where);
    ++rows;
  }
  if (rows != 4)
    throw FileError(name + ": expected 4 rows of a 4x4 pose matrix, got " + std::to_string(rows));
  return m;
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  std::ostringstream all;
  all << in.rdbuf();
  return all.str();
}

void write_pose_matrix(const std::string& path, const Eigen::Matrix4d& m) {
  std::ostringstream out;
  out.precision(17);
  for (int r = 0; r < 4; ++r)
    out << m(r, 0) << ' ' << m(r, 1) << ' ' << m(r, 2) << ' ' << m(r, 3) << '\n';
  write_file_atomically(path, out.str());
}

}  // namespace softhd
