#pragma once
/// \file enum_names.hpp
/// The names of softhd's enums in one place: a table of (value, name) pairs per enum, and one
/// pair of functions for both directions, so that a name is written once and every parser
/// refuses an unknown name with the same message, listing the valid ones:
///
///     constexpr EnumNames<Particles, 2> kParticleNames{{{Particles::nodes, "nodes"},
///                                                       {Particles::quadrature, "quadrature"}}};
///     enum_name(kParticleNames, Particles::nodes)          // "nodes"
///     enum_from_name(kParticleNames, "grid", "particles")  // throws InvalidArgument:
///         // unknown particles 'grid' (expected nodes or quadrature)
///
/// An enum whose values are 0, 1, ..., N-1 (no initialisers: declaration order) writes its
/// table as its last value and the list of names in that order:
///
///     constexpr auto kParticleNames =
///         enum_sequence<Particles::quadrature>({"nodes", "quadrature"});

#include <array>
#include <cstddef>
#include <string>
#include <utility>

#include "softhd/error.hpp"

namespace softhd {

/// The (value, name) table of an enum with N values.
template <class E, std::size_t N>
using EnumNames = std::array<std::pair<E, const char*>, N>;

namespace detail {
template <class E, std::size_t N, std::size_t... K>
constexpr EnumNames<E, N> enum_sequence(const char* const (&names)[N], std::index_sequence<K...>) {
  return {{{static_cast<E>(K), names[K]}...}};
}
}  // namespace detail

/// The table of an enum E whose values are 0, 1, ..., N-1, `Last` its last value:
/// names[k] is the name of E(k). A value inserted before `Last` without its name does not
/// compile.
template <auto Last, std::size_t N>
constexpr EnumNames<decltype(Last), N> enum_sequence(const char* const (&names)[N]) {
  static_assert(static_cast<std::size_t>(Last) + 1 == N, "one name per value, in order");
  return detail::enum_sequence<decltype(Last), N>(names, std::make_index_sequence<N>{});
}

/// The name of `value` in `names`; "unknown" if the table misses it (a bug).
template <class E, std::size_t N>
std::string enum_name(const EnumNames<E, N>& names, E value) {
  for (const auto& [v, name] : names)
    if (v == value) return name;
  return "unknown";
}

/// "a, b or c": the names of a table, for messages.
template <class E, std::size_t N>
std::string enum_choices(const EnumNames<E, N>& names) {
  std::string out;
  for (std::size_t k = 0; k < N; ++k) {
    if (k > 0) out += k + 1 == N ? " or " : ", ";
    out += names[k].second;
  }
  return out;
}

/// The value named `name`. Throws InvalidArgument "unknown <what> '<name>' (expected a, b or
/// c)" for any other name.
template <class E, std::size_t N>
E enum_from_name(const EnumNames<E, N>& names, const std::string& name, const std::string& what) {
  for (const auto& [v, n] : names)
    if (name == n) return v;
  throw InvalidArgument("unknown " + what + " '" + name + "' (expected " + enum_choices(names) +
                        ")");
}

}  // namespace softhd
