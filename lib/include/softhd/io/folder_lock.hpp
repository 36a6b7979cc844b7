#pragma once
/// \file folder_lock.hpp
/// An exclusive lock on an output folder (docs/guide.md, "The folder lock"): two runs that
/// write the same checkpoint, history and bodies would corrupt each other's files. The lock
/// is an flock(2) on DIR/.softhd.lock holding the owner's process id; the kernel releases
/// it when the process ends in any way (kill -9 included), so a stale lock file never
/// blocks a later run.

#include <string>

namespace softhd {

/// Holds the lock of one folder while alive.
class FolderLock {
 public:
  /// Locks `dir` (which must exist). Throws ResourceError naming the folder and the process
  /// that holds it if another process does, FileError if the lock file cannot be made.
  explicit FolderLock(const std::string& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace softhd
