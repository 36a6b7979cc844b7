#pragma once
/// \file cloud_io.hpp
/// Reading and writing point clouds (docs/formulation.md §1.1, §6.1) as text or PLY files.
///
/// Every problem with a file (missing, unreadable, malformed, a non-finite
/// coordinate, a volume <= 0, ...) throws softhd::FileError with a one-line
/// message naming the file and, where there is one, the line:
/// `cloud.txt:12: expected a number, got 'abc'`. A bad argument (e.g. `dim`
/// not 0, 2 or 3) throws softhd::InvalidArgument.

#include <string>

#include "softhd/point_cloud.hpp"

namespace softhd {

/// read_text_cloud() on bytes already in memory; `name` stands for the file in messages.
PointCloud parse_text_cloud(const std::string& data, const std::string& name, int dim = 0);
/// read_ply_cloud() on bytes already in memory; `name` stands for the file in messages.
PointCloud parse_ply_cloud(const std::string& data, const std::string& name);

/// Reads a cloud from `path`: PLY when the name ends in `.ply` (any case),
/// text otherwise. `dim` is 0 (decide from the file), 2 or 3; for a PLY file a
/// non-zero `dim` must agree with the file (z present <=> 3D).
PointCloud read_cloud(const std::string& path, int dim = 0);

/// Writes `cloud` with its volumes: binary PLY when the name ends in `.ply` (any case), text
/// otherwise (write_ply_cloud, write_text_cloud). Throws FileError if it cannot write.
void write_cloud(const std::string& path, const PointCloud& cloud);

/// Reads a text cloud: one point per line, `x y [z] [V]`, fields separated by
/// whitespace and/or single commas; `#` starts a comment (whole line or
/// trailing); blank lines are skipped; CRLF line ends are accepted.
///
/// Columns per line, which must be the same on every data line:
///  - dim = 0 (auto): 2 -> 2D (x y), 3 -> 3D (x y z), 4 -> 3D with volume (x y z V);
///  - dim = 2: 2 (x y) or 3 (x y V);
///  - dim = 3: 3 (x y z) or 4 (x y z V).
/// A missing V means V = 1. Note that a 2D cloud with volumes (3 columns) is
/// only read as such with dim = 2; with dim = 0 it would be read as 3D.
PointCloud read_text_cloud(const std::string& path, int dim = 0);

/// Reads a PLY cloud (`format ascii 1.0` or `format binary_little_endian 1.0`;
/// big-endian files are rejected). The `vertex` element must have scalar
/// properties `x` and `y`, optionally `z` (absent -> 2D) and `volume` (absent
/// -> V = 1), each of any PLY scalar type. Other properties (scalar or list)
/// and other elements (e.g. `face`, before or after `vertex`) are skipped.
/// Binary values are converted exactly to double; ascii values are read as the
/// decimal numbers they are (a `float` property's text is not rounded to float).
/// Data after the last element is an error in ascii files and ignored in binary.
PointCloud read_ply_cloud(const std::string& path);

/// Writes `cloud` as text: a `#` header line, then one point per line,
/// `x y [z] [V]` separated by single spaces. Numbers are written in the shortest
/// form that reads back to the identical double, so a text round trip is
/// bit-exact. A 2D cloud written with volumes has 3 columns: read it back with
/// dim = 2.
void write_text_cloud(const std::string& path, const PointCloud& cloud, bool with_volumes = true);

/// Writes `cloud` as PLY with one `vertex` element of `double` properties
/// x, y, [z,] volume: binary little-endian when `binary`, ascii otherwise
/// (shortest round-trip decimal form). Both round-trip bit-exactly.
void write_ply_cloud(const std::string& path, const PointCloud& cloud, bool binary = true);

}  // namespace softhd
