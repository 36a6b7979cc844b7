#pragma once
/// \file scene.hpp
/// Scene files (JSON, docs/formulation.md §5.1/§6.2): a name, the body (fe::Body: its mesh,
/// materials, fibres, clamp, control space and bounds) and the target, which belongs to the
/// optimiser and is kept as raw JSON text. Invalid files throw FileError naming the key and
/// what was expected.
///
///     { "name": "bending",
///       "mesh": { "type": "box", "lower": [0,0,0], "upper": [10,2,0.1],
///                 "cells": [50,5,2], "order": 2 },
///       "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
///       "fibers": [1,0,0],
///       "clamp": ["x0"],
///       "constraints": [ { "face": "z0", "components": [2] } ],      (optional)
///       "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
///       "target": { ... } }                                           (optional)
///
/// Material models: "mooney_rivlin" (a, b, c) and "transversely_isotropic" (a, b, c, d,
/// direction f as an array).
///
/// A body from Gmsh (docs/guide.md, "A body from Gmsh"):
///
///     "mesh": { "type": "gmsh", "file": "finger.msh", "order": 2, "scale": 1 },
///     "materials": { "body": {...}, "layer": {...} },     (or one "material")
///     "fibers": [1, 0, 0] | { "data": "fibres" } | { "file": "f.txt", "per": "element" },
///     "clamp": ["base"],
///     "control": { "space": "vertex", "region": "muscle", "lower": -1e5, "upper": 0 }

#include <string>

#include "softhd/fe/body.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd {

/// A parsed scene file (docs/guide.md lists every key).
struct Scene {
  std::string name;    ///< "name", or the file name
  std::string source;  ///< file name (for messages; relative target files are resolved against it)
  fe::Body body;       ///< the body: mesh, materials, fibres, constraints, control
  std::string target_json;  ///< raw "target" object, empty if absent
};

/// Parses JSON text; `source` names it in error messages (and is the body's source). Throws
/// FileError, and ResourceError (before building anything) if the mesh's estimated memory
/// exceeds `memory_limit` bytes (see fe::check_mesh_size).
Scene parse_scene(const std::string& json_text, const std::string& source,
                  double memory_limit = fe::kDefaultMemoryLimit);
/// Reads and parses a scene file. Throws FileError or ResourceError.
Scene load_scene(const std::string& path, double memory_limit = fe::kDefaultMemoryLimit);

}  // namespace softhd
