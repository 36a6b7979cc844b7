#pragma once
/// \file atomic_file.hpp
/// The one way softhd writes a file (docs/guide.md, "What softhd writes"): a regular file is
/// written to a temporary beside it and renamed over it, so a reader never sees a truncated
/// file; a device or pipe (/dev/stdout, /dev/full, a FIFO) is written directly. Every error,
/// including those only reported when the file is closed (a full disk), throws FileError
/// naming the file and the reason, and the temporary is removed.

#include <string>

namespace softhd {

/// Writes `bytes` to `path` as described above. Throws FileError.
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace softhd
