#pragma once
// Unknown-key checks for the project's JSON files (scenes, targets): a key that is not one
// of the allowed ones is refused, naming it, the keys allowed there and the closest one.
// "description" and "comment" are free keys, allowed in every object (docs/guide.md).
// Internal header (no nlohmann type in the public headers).

#include <algorithm>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "softhd/error.hpp"

namespace softhd::io {

// Levenshtein distance between a and b (single-row dynamic programme).
inline std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// The name in `names` closest to `name`, or "" if none is within a third of its length
// (at least 2 edits) — a likely typo, not any name.
inline std::string closest_name(const std::string& name, const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, name.size() / 3) + 1;
  for (const std::string& n : names) {
    const std::size_t d = edit_distance(name, n);
    if (d < best_d) best_d = d, best = n;
  }
  return best;
}

// "unknown key 'inital' (allowed: space, lower, upper, initial; did you mean 'initial'?)"
inline std::string unknown_key_message(const std::string& key,
                                       const std::vector<std::string>& allowed) {
  std::string list;
  for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
  const std::string near = closest_name(key, allowed);
  return "unknown key '" + key + "' (allowed: " + list +
         (near.empty() ? "" : "; did you mean '" + near + "'?") + ")";
}

// Throws FileError("<where>: <path>: unknown key ...") for the first key of `object` (a JSON
// object) that is neither in `allowed` nor a free key. `path` is the object's key path
// ("control", "constraints[1]"), "" for the top level.
inline void check_keys(const nlohmann::json& object, const std::string& where,
                       const std::string& path, std::initializer_list<const char*> allowed) {
  if (!object.is_object()) return;
  const std::vector<std::string> names(allowed.begin(), allowed.end());
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (key == "description" || key == "comment") continue;
    if (std::find(names.begin(), names.end(), key) != names.end()) continue;
    throw FileError(where + ": " + (path.empty() ? "" : "in '" + path + "': ") +
                    unknown_key_message(key, names));
  }
}

}  // namespace softhd::io
