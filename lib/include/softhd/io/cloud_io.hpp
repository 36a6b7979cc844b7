#pragma once
/// \file cloud_io.hpp
/// Reading and writing point clouds (docs/formulation.md §1.1, §6.1): text and PLY files,
/// and PCD files (PCL's format; read only).
///
/// Every problem with a file (missing, unreadable, malformed, a non-finite
/// coordinate, a volume <= 0, ...) throws softhd::FileError with a one-line
/// message naming the file and, where there is one, the line:
/// `cloud.txt:12: expected a number, got 'abc'`. A bad argument (e.g. `dim`
/// not 0, 2 or 3) throws softhd::InvalidArgument.
///
/// What a reader skips without failing (colours, normals and other properties; PCD's invalid
/// points) it reports as one-line notes naming the file, appended to `notes` when the caller
/// passes a list (the command line prints them on stderr).

#include <string>
#include <vector>

#include "softhd/point_cloud.hpp"

namespace softhd {

/// read_text_cloud() on bytes already in memory; `name` stands for the file in messages.
PointCloud parse_text_cloud(const std::string& data, const std::string& name, int dim = 0,
                            std::vector<std::string>* notes = nullptr);
/// read_ply_cloud() on bytes already in memory; `name` stands for the file in messages.
PointCloud parse_ply_cloud(const std::string& data, const std::string& name,
                           std::vector<std::string>* notes = nullptr);
/// read_pcd_cloud() on bytes already in memory; `name` stands for the file in messages.
PointCloud parse_pcd_cloud(const std::string& data, const std::string& name,
                           std::vector<std::string>* notes = nullptr);

/// Reads a cloud from `path`: PLY when the name ends in `.ply`, PCD when it ends in `.pcd`
/// (any case), text otherwise. `dim` is 0 (decide from the file), 2 or 3; for a PLY or PCD
/// file a non-zero `dim` must agree with the file (z present <=> 3D; PCD is always 3D).
PointCloud read_cloud(const std::string& path, int dim = 0,
                      std::vector<std::string>* notes = nullptr);

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
/// A 3D line may carry 3 or 6 more columns (colours and/or normals, as other tools write
/// them): 6 or 9 columns are x y z and 7 or 10 are x y z V, the rest skipped (not parsed)
/// with a note.
PointCloud read_text_cloud(const std::string& path, int dim = 0,
                           std::vector<std::string>* notes = nullptr);

/// Reads a PLY cloud (`format ascii 1.0` or `format binary_little_endian 1.0`;
/// big-endian files are rejected). The `vertex` element must have scalar
/// properties `x` and `y`, optionally `z` (absent -> 2D) and `volume` (absent
/// -> V = 1), each of any PLY scalar type. Other properties (scalar or list)
/// and other elements (e.g. `face`, before or after `vertex`) are skipped.
/// Binary values are converted exactly to double; ascii values are read as the
/// decimal numbers they are (a `float` property's text is not rounded to float).
/// Data after the last element is an error in ascii files and ignored in binary.
/// Skipped vertex properties (colours, normals, ...) are named in a note.
PointCloud read_ply_cloud(const std::string& path, std::vector<std::string>* notes = nullptr);

/// Reads a PCD cloud (PCL's format; `DATA ascii`, `binary` or `binary_compressed`, the last
/// LZF-compressed with the fields stored one after the other). Header lines FIELDS, SIZE,
/// TYPE (F, I, U), COUNT (default 1), WIDTH, HEIGHT (default 1), POINTS (default WIDTH ×
/// HEIGHT, else equal to it), VIEWPOINT (ignored, with a note unless the identity), DATA;
/// `#` comments. Fields x, y, z are required (COUNT 1, any type); the first of `volume`,
/// `weight`, `area` present gives the volumes (absent: 1); every other field (rgb,
/// normal_x, intensity, ...) is skipped with a note. A point whose x, y and z are all NaN
/// (PCL's invalid point, as in organised clouds) is dropped with a note; any other
/// non-finite value is an error naming the line (ascii) or the point (binary).
PointCloud read_pcd_cloud(const std::string& path, std::vector<std::string>* notes = nullptr);

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
