// Field tables: each settings or component struct that a file, `--set`, the editor or the docs can
// reach declares its fields once, beside the struct, as a constexpr table of Field rows (key,
// member, range, rules, a one-line doc); each enumeration declares its value names once beside
// the enum. Everything else is derived from those declarations: the JSON reader and writer
// (runtime/core/field_io.h), range validation (validate_fields() below), `--set` (it goes through
// the reader), the editor's widgets and limits (the reader records them), the JSON Schema and the
// settings reference (`kaskad schema`). Only rules across fields stay hand-written.
//
// Declaring a table for struct S (found by argument-dependent lookup in S's namespace):
//   constexpr auto field_table(fields::Of<S>) {
//     return std::tuple{fields::integer("count", &S::count, 1, 8, "Cascades per light"), ...};
//   }
// and the names of enum E, in the enum's order, with the count tied to its last value:
//   constexpr std::array<std::string_view, 3> enum_names(E) { return {"a", "b", "c"}; }
//   static_assert(enum_names(E{}).size() == std::size_t(E::c) + 1);
// This header is std-only (layer `fields`, below core and components).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>

namespace kaskad::fields {

/// A tag naming struct S for field_table() lookups.
template <class S>
struct Of {};

/// Rules a field keeps beyond its range, as bits of Field::rules.
enum Rule : std::uint32_t {
  kPowerOfTwo = 1u << 0,  ///< an integer that is also a power of two (map sizes, sample counts)
  kOdd = 1u << 1,         ///< an odd integer (blur sides)
  kBelowHi = 1u << 2,     ///< a number in [lo, hi): hi itself is refused
  kAutoIsZero = 1u << 3,  ///< files may also say "auto", read as 0 (0 means "automatic")
  kShared = 1u << 4,      ///< shadow settings: every shadowed light takes the first one's value
  kDebug = 1u << 5,       ///< a debug view or toggle, off in shipped scenes
};

/// What kind of value a field holds, from its member type.
enum class Kind { boolean, integer, number, vector, enumeration, text };

/// An enumeration with value names: enum_names(E{}) returns them in the enum's order.
template <class E>
concept NamedEnum = std::is_enum_v<E> && requires(E e) { enum_names(e); };

/// A float vector of fixed size (glm::vec2/3/4: M::length(), M::value_type float).
template <class M>
struct VectorTraits {
  static constexpr int size = 0;
};
template <class M>
  requires(std::is_same_v<typename M::value_type, float> && (M::length() > 0))
struct VectorTraits<M> {
  static constexpr int size = int(M::length());
};

template <class M>
constexpr Kind kind_of() {
  if constexpr (std::is_same_v<M, bool>) return Kind::boolean;
  else if constexpr (std::is_same_v<M, int>) return Kind::integer;
  else if constexpr (std::is_same_v<M, float>) return Kind::number;
  else if constexpr (std::is_same_v<M, std::string>) return Kind::text;
  else if constexpr (std::is_enum_v<M>) return Kind::enumeration;
  else {
    static_assert(VectorTraits<M>::size > 0, "a field is bool, int, float, std::string, an enum "
                                             "with enum_names() or a glm float vector");
    return Kind::vector;
  }
}

/// One field of struct S: its key in files and `--set`, the member, the range of numbers (each
/// number of a vector; inclusive unless kBelowHi), rules and a one-line doc. The default is the
/// member's initialiser (S{}.*member).
template <class S, class M>
struct Field {
  using Struct = S;
  using Member = M;
  static constexpr Kind kind = kind_of<M>();
  std::string_view key;
  M S::*member;
  double lo = 0.0, hi = 0.0;
  std::uint32_t rules = 0;
  std::string_view doc;

  constexpr bool has(Rule r) const { return (rules & r) != 0; }
};

// Row builders, one per kind, so that a table reads as a list of declarations.
template <class S>
constexpr Field<S, bool> flag(std::string_view key, bool S::*m, std::string_view doc,
                              std::uint32_t rules = 0) {
  return {key, m, 0.0, 1.0, rules, doc};
}
template <class S>
constexpr Field<S, int> integer(std::string_view key, int S::*m, double lo, double hi,
                                std::string_view doc, std::uint32_t rules = 0) {
  return {key, m, lo, hi, rules, doc};
}
template <class S>
constexpr Field<S, float> number(std::string_view key, float S::*m, double lo, double hi,
                                 std::string_view doc, std::uint32_t rules = 0) {
  return {key, m, lo, hi, rules, doc};
}
template <class S, class V>
  requires(VectorTraits<V>::size > 0)
constexpr Field<S, V> vector(std::string_view key, V S::*m, double lo, double hi,
                             std::string_view doc) {
  return {key, m, lo, hi, 0, doc};
}
template <class S, NamedEnum E>
constexpr Field<S, E> choice(std::string_view key, E S::*m, std::string_view doc,
                             std::uint32_t rules = 0) {
  return {key, m, 0.0, 0.0, rules, doc};
}
template <class S>
constexpr Field<S, std::string> text(std::string_view key, std::string S::*m,
                                     std::string_view doc) {
  return {key, m, 0.0, 0.0, 0, doc};
}

/// The table of S.
template <class S>
constexpr auto table() {
  return field_table(Of<S>{});
}

/// Calls visit(field) for every row of S's table, in order.
template <class S, class Visit>
constexpr void for_each_field(Visit&& visit) {
  std::apply([&](const auto&... f) { (visit(f), ...); }, table<S>());
}

/// The name of enum value e ("?" outside the table).
template <NamedEnum E>
constexpr std::string_view name_of(E e) {
  const auto names = enum_names(E{});
  const auto i = std::size_t(e);
  return i < names.size() ? names[i] : std::string_view("?");
}

/// The value named `name`; false when no value has that name.
template <NamedEnum E>
constexpr bool value_named(std::string_view name, E& out) {
  const auto names = enum_names(E{});
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) {
      out = E(i);
      return true;
    }
  return false;
}

/// "a, b or c".
template <std::size_t N>
std::string list_names(const std::array<std::string_view, N>& names) {
  std::string s;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) s += i + 1 == N ? " or " : ", ";
    s += names[i];
  }
  return s;
}

/// Shortest readable form of a bound or value ("1.2", not "1.200000").
inline std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// The range as users read it: "[1, 8]", "[0, 1)".
template <class F>
std::string range_text(const F& f) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on "[" + std::string&&.
  std::string s(1, '[');
  s += format_number(f.lo);
  s += ", ";
  s += format_number(f.hi);
  s += f.has(kBelowHi) ? ')' : ']';
  return s;
}

/// Empty when value v of field f keeps its range and rules, else a message starting with the
/// key, e.g. "lambda must be in [0, 1], was 1.2". NaN is out of every range.
template <class F>
std::string check_value(const F& f, const typename F::Member& v) {
  using M = typename F::Member;
  const std::string key(f.key);
  if constexpr (std::is_same_v<M, int>) {
    const bool in = v >= f.lo && v <= f.hi;
    if (f.has(kPowerOfTwo) && (!in || (v & (v - 1)) != 0))
      return key + " must be a power of two in " + range_text(f) + ", was " + std::to_string(v);
    if (f.has(kOdd) && (!in || v % 2 == 0))
      return key + " must be an odd integer in " + range_text(f) + ", was " + std::to_string(v);
    if (!in) return key + " must be in " + range_text(f) + ", was " + std::to_string(v);
  } else if constexpr (std::is_same_v<M, float>) {
    const double d = double(v);
    const bool in = d >= f.lo && (f.has(kBelowHi) ? d < f.hi : d <= f.hi);
    if (!in) return key + " must be in " + range_text(f) + ", was " + format_number(d);
  } else if constexpr (std::is_enum_v<M>) {
    const auto names = enum_names(M{});
    if (std::size_t(v) >= names.size())
      return key + " must be " + list_names(names) + ", was " + std::to_string(int(v));
  } else if constexpr (VectorTraits<M>::size > 0) {
    for (int i = 0; i < VectorTraits<M>::size; ++i)
      if (!(double(v[i]) >= f.lo && double(v[i]) <= f.hi))
        return key + " must have every component in " + range_text(f) + ", was " +
               format_number(double(v[i])) + " at " + std::to_string(i);
  }
  return {};
}

/// Empty when every field of s keeps its range and rules, else the first field's message.
template <class S>
std::string validate_fields(const S& s) {
  std::string bad;
  for_each_field<S>([&](const auto& f) {
    if (bad.empty()) bad = check_value(f, s.*f.member);
  });
  return bad;
}

}  // namespace kaskad::fields
