#pragma once
/// \file pose_io.hpp
/// A scan's pose as a text file of its 4×4 matrix (docs/formulation.md §8.4): four lines of four
/// numbers (whitespace or single commas between them), `#` comments and blank lines skipped.
/// Problems throw softhd::FileError naming the file and line. The matrix only: whether it is a
/// pose (scan::Pose::from_matrix) is checked by control/pose_file.hpp, which names the file.

#include <Eigen/Core>
#include <string>

namespace softhd {

/// The 4×4 matrix in `text`; `name` stands for the file in messages: "pose.txt:3: expected 4
/// numbers, got 3", "pose.txt: expected 4 rows of a 4x4 pose matrix, got 5".
Eigen::Matrix4d parse_pose_matrix(const std::string& text, const std::string& name);
/// The whole text of the file at `path` (FileError "cannot open ..." if it cannot be read).
std::string read_text_file(const std::string& path);
/// Writes the 4×4 matrix, one row per line, 17 significant digits (a round trip gives the same
/// matrix to rounding).
void write_pose_matrix(const std::string& path, const Eigen::Matrix4d& m);

}  // namespace softhd
