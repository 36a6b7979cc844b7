#pragma once
// A number as text for an error message (internal): the scene-file and run checks.

#include <cstdio>
#include <string>

namespace softhd::detail {

/// v as a decimal of 10 significant digits ("%.10g").
inline std::string decimal(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

}  // namespace softhd::detail
