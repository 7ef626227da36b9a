// JSON for field tables (runtime/fields/fields.h): one reader, one writer and one JSON Schema for
// every struct with a field_table(), so a field declared in its table is read (range, rules,
// unknown keys, JSON-pointer errors), written (non-defaults only), recorded for the editor and
// documented without another line.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "runtime/core/json_reader.h"
#include "runtime/fields/fields.h"

namespace kaskad::field_io {

using json = nlohmann::json;

/// The names of E with their values, for ObjectReader::enumeration().
template <class E>
std::vector<std::pair<std::string, E>> name_table() {
  std::vector<std::pair<std::string, E>> out;
  const auto names = enum_names(E{});
  for (std::size_t i = 0; i < names.size(); ++i) out.emplace_back(std::string(names[i]), E(i));
  return out;
}

namespace detail {

/// An enumeration's names as the file writes them: a name made of digits is a JSON integer
/// (pcf_kernel's box sides 3, 5, 7, 9), any other a string.
inline json name_json(std::string_view name) {
  const bool digits = !name.empty() && name.find_first_not_of("0123456789") == std::string::npos;
  return digits ? json(std::stoi(std::string(name))) : json(std::string(name));
}

template <class F>
void read_field(json_reader::ObjectReader& r, const F& f, typename F::Struct& s) {
  using M = typename F::Member;
  const std::string key(f.key);
  M& out = s.*f.member;
  if constexpr (std::is_same_v<M, bool>) {
    r.boolean(key.c_str(), out);
  } else if constexpr (std::is_same_v<M, int>) {
    if (f.has(fields::kPowerOfTwo)) {
      r.power_of_two(key.c_str(), out, int(f.lo), int(f.hi));
    } else {
      r.integer(key.c_str(), out, int(f.lo), int(f.hi));
      if (f.has(fields::kOdd) && r.has(key.c_str()) && out % 2 == 0)
        json_reader::fail(r.at(key.c_str()), "must be an odd integer in " + fields::range_text(f) +
                                                 ", was " + std::to_string(out));
    }
  } else if constexpr (std::is_same_v<M, float>) {
    if (f.has(fields::kAutoIsZero) && r.has(key.c_str()) && r.raw(key.c_str()) == "auto") {
      out = 0.0f;
      return;
    }
    // [lo, hi): the largest float under hi is the bound (the editor's too).
    const float hi = f.has(fields::kBelowHi) ? std::nextafter(float(f.hi), float(f.lo)) : float(f.hi);
    if (f.has(fields::kBelowHi) && r.has(key.c_str()) && r.raw(key.c_str()).is_number() &&
        r.raw(key.c_str()).template get<double>() > double(hi))
      json_reader::fail(r.at(key.c_str()), "must be in " + fields::range_text(f) + ", was " +
                                               r.raw(key.c_str()).dump());
    r.number(key.c_str(), out, float(f.lo), hi);
  } else if constexpr (std::is_same_v<M, std::string>) {
    r.string(key.c_str(), out);
  } else if constexpr (std::is_enum_v<M>) {
    r.enumeration(key.c_str(), out, name_table<M>());
  } else {
    r.template vector<fields::VectorTraits<M>::size>(key.c_str(), out, float(f.lo), float(f.hi));
  }
}

template <class M>
json value_json(const M& v) {
  if constexpr (std::is_same_v<M, float>) return json_reader::num(v);
  else if constexpr (std::is_enum_v<M>) return name_json(fields::name_of(v));
  else if constexpr (fields::VectorTraits<M>::size > 0) return json_reader::vec(v);
  else return json(v);
}

}  // namespace detail

/// Reads every field of S's table that the object holds into s, in table order; fields it does
/// not name keep their values. Does not call finish(): the caller reads its hand-written keys
/// and cross-field rules first.
template <class S>
void read_fields(json_reader::ObjectReader& r, S& s) {
  fields::for_each_field<S>([&](const auto& f) { detail::read_field(r, f, s); });
}

/// The fields of s as a JSON object, in table order: all of them, or with `defaults` only those
/// that differ from it.
template <class S>
json write_fields(const S& s, const S* defaults = nullptr) {
  json j = json::object();
  fields::for_each_field<S>([&](const auto& f) {
    if (!defaults || !(s.*f.member == defaults->*f.member))
      j[std::string(f.key)] = detail::value_json(s.*f.member);
  });
  return j;
}

/// The JSON Schema of one field (type, range, names, default, description).
template <class F>
json field_schema(const F& f) {
  using M = typename F::Member;
  const typename F::Struct defaults{};
  json j;
  j["description"] = std::string(f.doc);
  j["default"] = detail::value_json(defaults.*f.member);
  if constexpr (std::is_same_v<M, bool>) {
    j["type"] = "boolean";
  } else if constexpr (std::is_same_v<M, int>) {
    j["type"] = "integer";
    j["minimum"] = int(f.lo);
    j["maximum"] = int(f.hi);
    if (f.has(fields::kPowerOfTwo)) {
      json values = json::array();
      for (long long v = 1; v <= (long long)f.hi; v *= 2)
        if (v >= f.lo) values.push_back(v);
      j["enum"] = values;
    }
    if (f.has(fields::kOdd)) j["not"] = {{"multipleOf", 2}};
  } else if constexpr (std::is_same_v<M, float>) {
    j["type"] = "number";
    j["minimum"] = f.lo;
    j[f.has(fields::kBelowHi) ? "exclusiveMaximum" : "maximum"] = f.hi;
    if (f.has(fields::kAutoIsZero)) {
      json number = j;
      number.erase("description");
      number.erase("default");
      j = {{"description", j["description"]}, {"default", j["default"]},
           {"anyOf", {number, {{"const", "auto"}}}}};
    }
  } else if constexpr (std::is_same_v<M, std::string>) {
    j["type"] = "string";
  } else if constexpr (std::is_enum_v<M>) {
    json values = json::array();
    for (std::string_view n : enum_names(M{})) values.push_back(detail::name_json(n));
    j["enum"] = values;
  } else {
    constexpr int n = fields::VectorTraits<M>::size;
    j["type"] = "array";
    j["minItems"] = n;
    j["maxItems"] = n;
    j["items"] = {{"type", "number"}, {"minimum", f.lo}, {"maximum", f.hi}};
  }
  return j;
}

/// The "properties" of S's table for a JSON Schema object.
template <class S>
json schema_properties() {
  json props = json::object();
  fields::for_each_field<S>([&](const auto& f) { props[std::string(f.key)] = field_schema(f); });
  return props;
}

/// Markdown rows "| key | type | default | range or values | doc | notes |" of S's table, for
/// the settings reference (notes: shared, debug).
template <class S>
std::string reference_rows() {
  std::string out;
  fields::for_each_field<S>([&](const auto& f) {
    using M = typename std::decay_t<decltype(f)>::Member;
    const json s = field_schema(f);
    std::string type, range;
    if constexpr (std::is_same_v<M, bool>) {
      type = "boolean";
    } else if constexpr (std::is_same_v<M, int>) {
      type = "integer";
      range = fields::range_text(f);
      if (f.has(fields::kPowerOfTwo)) range = "power of two in " + range;
      if (f.has(fields::kOdd)) range = "odd, in " + range;
    } else if constexpr (std::is_same_v<M, float>) {
      type = "number";
      range = fields::range_text(f);
      if (f.has(fields::kAutoIsZero)) range += ", or \"auto\" (0)";
    } else if constexpr (std::is_same_v<M, std::string>) {
      type = "string";
    } else if constexpr (std::is_enum_v<M>) {
      type = "name";
      for (std::string_view n : enum_names(M{})) range += (range.empty() ? "`" : ", `") + std::string(n) + "`";
    } else {
      type = std::to_string(fields::VectorTraits<M>::size) + " numbers";
      range = "each in " + fields::range_text(f);
    }
    std::string notes;
    if (f.has(fields::kShared)) notes = "shared";
    if (f.has(fields::kDebug)) notes += notes.empty() ? "debug" : ", debug";
    out += "| `" + std::string(f.key) + "` | " + type + " | `" + s["default"].dump() + "` | " +
           range + " | " + std::string(f.doc) + " | " + notes + " |\n";
  });
  return out;
}

}  // namespace kaskad::field_io
