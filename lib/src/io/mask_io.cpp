#include "softhd/io/mask_io.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "softhd/error.hpp"

namespace softhd {

namespace {
// The line without its comment, CR and surrounding blanks.
std::string trimmed(std::string line) {
  const std::size_t hash = line.find('#');
  if (hash != std::string::npos) line.erase(hash);
  const char* blanks = " \t\r";
  const std::size_t first = line.find_first_not_of(blanks);
  if (first == std::string::npos) return {};
  return line.substr(first, line.find_last_not_of(blanks) - first + 1);
}
}  // namespace

Eigen::Array<bool, Eigen::Dynamic, 1> parse_mask(const std::string& data, const std::string& name) {
  std::vector<bool> entries;
  std::istringstream in(data);
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    const std::string field = trimmed(line);
    if (field.empty()) continue;
    if (field != "0" && field != "1")
      throw FileError(name + ":" + std::to_string(number) + ": expected 0 or 1, got '" + field +
                      "'");
    entries.push_back(field == "1");
  }
  if (entries.empty()) throw FileError(name + ": no entries (expected one 0 or 1 per line)");
  Eigen::Array<bool, Eigen::Dynamic, 1> mask(static_cast<Eigen::Index>(entries.size()));
  for (std::size_t i = 0; i < entries.size(); ++i) mask[static_cast<Eigen::Index>(i)] = entries[i];
  return mask;
}

Eigen::Array<bool, Eigen::Dynamic, 1> read_mask(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  std::ostringstream data;
  data << file.rdbuf();
  if (file.bad()) throw FileError("cannot read '" + path + "'");
  return parse_mask(data.str(), path);
}

}  // namespace softhd
