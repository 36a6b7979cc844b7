#include "softhd/io/atomic_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "softhd/error.hpp"

namespace softhd {

namespace {

// Writes all bytes to a newly opened `path` and closes it; returns 0 or the errno of the
// first failure (fwrite, fflush or fclose: a full disk may show only at the close).
int write_all(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return errno != 0 ? errno : EIO;
  int err = 0;
  if (std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) err = errno != 0 ? errno : EIO;
  if (std::fflush(f) != 0 && err == 0) err = errno != 0 ? errno : EIO;
  if (std::fclose(f) != 0 && err == 0) err = errno != 0 ? errno : EIO;
  return err;
}

// A temporary name beside `path`, unique within this process and among processes.
std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    // A device or a pipe: no rename (it would replace the device node).
    if (const int err = write_all(path, bytes))
      throw FileError("cannot write '" + path + "': " + std::strerror(err));
    return;
  }
  const std::string tmp = temporary_name(path);
  if (const int err = write_all(tmp, bytes)) {
    std::remove(tmp.c_str());
    throw FileError("cannot write '" + path + "': " + std::strerror(err));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw FileError("cannot write '" + path + "': " + std::strerror(err));
  }
}

}  // namespace softhd
