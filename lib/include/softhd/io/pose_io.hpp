#pragma once
/// \file pose_io.hpp
/// Reading and writing a scan's pose (docs/formulation.md §8.4) as a text file of its 4×4
/// matrix: four lines of four numbers (whitespace or single commas between them), `#`
/// comments and blank lines skipped. Problems throw softhd::FileError naming the file and line.

#include <string>

#include "softhd/scan/pose.hpp"

namespace softhd {

/// The pose of the matrix in `text` (Pose::from_matrix); `name` stands for the file in
/// messages: "pose.txt:3: expected 4 numbers, got 3", "pose.txt: expected 4 rows, got 5",
/// "pose.txt: pose matrix entry (4, 2) is 0.5, expected 0 ...".
scan::Pose parse_pose(const std::string& text, const std::string& name);
/// parse_pose() of the file at `path`.
scan::Pose read_pose(const std::string& path);
/// Writes the pose's 4×4 matrix, one row per line, 17 significant digits (a round trip
/// gives the same matrix to rounding).
void write_pose(const std::string& path, const scan::Pose& pose);

}  // namespace softhd
