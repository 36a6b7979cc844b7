// A scan's pose read from and written to its text file (docs/formulation.md §8.4).

#include "softhd/control/pose_file.hpp"

#include "softhd/error.hpp"
#include "softhd/io/pose_io.hpp"

namespace softhd {

scan::Pose parse_pose(const std::string& text, const std::string& name) {
  const Eigen::Matrix4d m = parse_pose_matrix(text, name);
  try {
    return scan::Pose::from_matrix(m);
  } catch (const InvalidArgument& e) {
    throw FileError(name + ": " + e.what());
  }
}

scan::Pose read_pose(const std::string& path) { return parse_pose(read_text_file(path), path); }

void write_pose(const std::string& path, const scan::Pose& pose) {
  write_pose_matrix(path, pose.matrix());
}

}  // namespace softhd
