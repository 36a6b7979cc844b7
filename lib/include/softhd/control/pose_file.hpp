#pragma once
/// \file pose_file.hpp
/// A scan's pose read from and written to its text file (io/pose_io.hpp holds the format):
/// the 4×4 matrix checked to be a pose, the file named in every message.

#include <string>

#include "softhd/scan/pose.hpp"

namespace softhd {

/// The pose of the matrix in `text` (scan::Pose::from_matrix); `name` stands for the file in
/// messages: "pose.txt:3: expected 4 numbers, got 3", "pose.txt: expected 4 rows, got 5",
/// "pose.txt: pose matrix entry (4, 2) is 0.5, expected 0 ...". Throws FileError.
scan::Pose parse_pose(const std::string& text, const std::string& name);
/// parse_pose() of the file at `path`.
scan::Pose read_pose(const std::string& path);
/// Writes the pose's 4×4 matrix (write_pose_matrix).
void write_pose(const std::string& path, const scan::Pose& pose);

}  // namespace softhd
