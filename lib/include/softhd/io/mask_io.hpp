#pragma once
/// \file mask_io.hpp
/// Reading a per-point mask (e.g. the camera mask DistanceForm::camera_mask: the moving points
/// a camera sees, docs/formulation.md §8.2) from a text file: one `0` or `1` per line, `#`
/// comments (whole line or trailing), blank lines skipped, CRLF accepted. Every problem throws
/// softhd::FileError naming the file and, where there is one, the line:
/// `camera_mask.txt:3: expected 0 or 1, got '2'`.

#include <Eigen/Core>
#include <string>

namespace softhd {

/// read_mask() on bytes already in memory; `name` stands for the file in messages.
Eigen::Array<bool, Eigen::Dynamic, 1> parse_mask(const std::string& data, const std::string& name);

/// The mask in the text file `path` (one entry per data line, in order).
Eigen::Array<bool, Eigen::Dynamic, 1> read_mask(const std::string& path);

}  // namespace softhd
