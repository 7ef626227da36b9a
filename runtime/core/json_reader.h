// Helpers for reading validated JSON content files (scenes, materials, the feature manifest):
// typed getters with ranges, unknown-key detection listing the valid keys, and JSON-path error
// locations. Parsers throw ContentError internally and convert it to kaskad::Error at their API.
#pragma once

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "runtime/core/file_io.h"
#include "runtime/result/result.h"

namespace kaskad::json_reader {

using json = nlohmann::json;

/// A content error inside a parser: thrown by fail() and turned into a kaskad::Error (with the
/// file name) at the parser's public function; it never escapes a public API.
struct ContentError {
  std::string where;
  std::string message;
};

[[noreturn]] inline void fail(const std::string& where, const std::string& message) {
  throw ContentError{where, message};
}

inline std::string type_name(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned: return "an integer";
    case json::value_t::number_float: return "a number";
    case json::value_t::string: return "a string";
    case json::value_t::array: return "an array";
    case json::value_t::object: return "an object";
    default: return "a value";
  }
}

inline std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

// Shortest decimal form of a float, as a double: files read 0.1, not 0.10000000149011612, and
// a load -> save -> load -> save cycle writes identical text.
inline double num(float f) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, f);
  double d = 0.0;
  std::from_chars(buf, r.ptr, d);
  return d;
}
inline json vec(const glm::vec2& v) { return json::array({num(v.x), num(v.y)}); }
inline json vec(const glm::vec3& v) { return json::array({num(v.x), num(v.y), num(v.z)}); }
inline json vec(const glm::vec4& v) { return json::array({num(v.x), num(v.y), num(v.z), num(v.w)}); }

/// While one exists, collects on its thread every enumerated field the readers are asked for (given
/// in the file or not) with the names their table accepts, and every range-checked number with
/// its bounds: the editor's combo boxes and drag fields take the readers' own tables and limits
/// instead of copies. Scoped: the previous recorder is restored when it ends.
class FieldRecorder {
 public:
  FieldRecorder() : previous_(current_) { current_ = this; }
  ~FieldRecorder() { current_ = previous_; }
  FieldRecorder(const FieldRecorder&) = delete;
  FieldRecorder& operator=(const FieldRecorder&) = delete;

  /// The recorder of this thread, or nullptr.
  static FieldRecorder* current() { return current_; }
  /// The bounds a number (or each number of an array) must lie in, inclusive.
  struct Range {
    double lo = 0.0, hi = 0.0;
    bool power_of_two = false;  ///< an integer that must also be a power of two (map sizes)
    bool operator==(const Range&) const = default;
  };
  void record(const std::string& path, std::vector<std::string> names) {
    enumerations_[path] = std::move(names);
  }
  void record(const std::string& path, Range range) { ranges_[path] = range; }
  /// The accepted names by field path as the reader names it in errors ("/shadow/filter",
  /// "/entities/2/light/type"), in the table's order.
  const std::map<std::string, std::vector<std::string>>& enumerations() const {
    return enumerations_;
  }
  /// The bounds of each range-checked number or array of numbers, by field path.
  const std::map<std::string, Range>& ranges() const { return ranges_; }

  /// The last two parts of a field's path, "/" or "." separated ("/entities/2/light/type" and
  /// "sun.light.type" give "light.type"; "/shadow/filter" and "shadow.filter" give
  /// "shadow.filter"): the object and the field, which name one table and one range of the
  /// readers whichever entity holds them (how the editor finds a field's).
  static std::string object_and_field(const std::string& path, char separator) {
    const auto last = path.rfind(separator);
    if (last == std::string::npos || last == 0) return path.substr(last == 0 ? 1 : 0);
    const auto before = path.rfind(separator, last - 1);
    std::string key = path.substr(before == std::string::npos ? 0 : before + 1);
    std::replace(key.begin(), key.end(), separator, '.');
    return key;
  }

 private:
  static inline thread_local FieldRecorder* current_ = nullptr;
  FieldRecorder* previous_;
  std::map<std::string, std::vector<std::string>> enumerations_;
  std::map<std::string, Range> ranges_;
};

// Reads the fields of one JSON object, tracking which keys were used so that unknown keys are
// reported with the list of valid ones.
class ObjectReader {
 public:
  ObjectReader(const json& j, std::string path) : j_(j), path_(std::move(path)) {
    if (!j.is_object()) fail(path_, "expected an object, got " + type_name(j));
  }

  bool has(const char* key) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
    return j_.contains(key);
  }
  const json& raw(const char* key) { return j_.at(key); }
  /// The whole object, for blocks keyed by names the content chooses (animation clips).
  const json& raw_object() const { return j_; }
  std::string at(const char* key) const { return path_ + "/" + key; }

  void number(const char* key, float& out, float lo, float hi) {
    record_range(key, lo, hi);
    if (!has(key)) return;
    const json& v = j_.at(key);
    if (!v.is_number()) fail(at(key), "expected a number, got " + type_name(v));
    out = float_in_range(v.get<double>(), lo, hi, at(key));
  }
  void integer(const char* key, int& out, int lo, int hi) {
    record_range(key, lo, hi);
    if (!has(key)) return;
    const json& v = j_.at(key);
    if (!v.is_number_integer()) fail(at(key), "expected an integer, got " + type_name(v));
    const long long d = v.get<long long>();
    if (d < lo || d > hi)
      fail(at(key), "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                        "], was " + std::to_string(d));
    out = int(d);
  }
  /// integer(), and a power of two (map sizes): `KEY must be a power of two in [lo, hi], was N`.
  void power_of_two(const char* key, int& out, int lo, int hi) {
    integer(key, out, lo, hi);
    record_range(key, lo, hi, /*power_of_two=*/true);
    if (has(key) && (out & (out - 1)) != 0)
      fail(at(key), std::string(key) + " must be a power of two in [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "], was " + std::to_string(out));
  }
  void boolean(const char* key, bool& out) {
    if (!has(key)) return;
    const json& v = j_.at(key);
    if (!v.is_boolean()) fail(at(key), "expected true or false, got " + type_name(v));
    out = v.get<bool>();
  }
  void string(const char* key, std::string& out) {
    if (!has(key)) return;
    const json& v = j_.at(key);
    if (!v.is_string()) fail(at(key), "expected a string, got " + type_name(v));
    out = v.get<std::string>();
  }
  template <int N>
  void vector(const char* key, glm::vec<N, float>& out, float lo, float hi) {
    record_range(key, lo, hi);
    if (!has(key)) return;
    const json& v = j_.at(key);
    if (!v.is_array() || v.size() != N)
      fail(at(key), "expected an array of " + std::to_string(N) + " numbers, got " + type_name(v) +
                        (v.is_array() ? " of " + std::to_string(v.size()) : ""));
    for (int i = 0; i < N; ++i) {
      if (!v[std::size_t(i)].is_number())
        fail(at(key) + "/" + std::to_string(i), "expected a number, got " + type_name(v[std::size_t(i)]));
      out[i] = float_in_range(v[std::size_t(i)].get<double>(), lo, hi,
                              at(key) + "/" + std::to_string(i));
    }
  }
  /// One of the table's names. A name made of digits is given as that JSON integer (pcf_kernel's
  /// box sides: 3, 5, 7, 9).
  template <class E, class Name>
  void enumeration(const char* key, E& out, const std::vector<std::pair<Name, E>>& table) {
    std::vector<std::string> names;
    for (const auto& [n, e] : table) names.push_back(n);
    if (FieldRecorder* recorder = FieldRecorder::current()) recorder->record(at(key), names);
    if (!has(key)) return;
    const json& v = j_.at(key);
    const bool integer_names = std::any_of(names.begin(), names.end(), [](const std::string& n) {
      return !n.empty() && n.find_first_not_of("0123456789") == std::string::npos;
    });
    std::string given;
    if (v.is_string()) given = v.get<std::string>();
    else if (integer_names && v.is_number_integer()) given = v.dump();
    else fail(at(key), "expected one of " + join(names) + ", got " + type_name(v));
    for (const auto& [n, e] : table)
      if (given == n) {
        out = e;
        return;
      }
    fail(at(key), "unknown value " + (v.is_string() ? "'" + given + "'" : given) +
                      "; expected one of " + join(names));
  }
  /// Fails on keys that no reader asked for.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (std::find(known_.begin(), known_.end(), it.key()) == known_.end())
        fail(at(it.key().c_str()), "unknown key '" + it.key() + "'; valid keys here: " +
                                       join(known_));
    }
  }

 private:
  void record_range(const char* key, double lo, double hi, bool power_of_two = false) const {
    if (FieldRecorder* recorder = FieldRecorder::current())
      recorder->record(at(key), {lo, hi, power_of_two});
  }
  static std::string fmt(double d) {
    std::ostringstream s;
    s << d;
    return s.str();
  }
  // `d` as the float it is stored as, which must lie in [lo, hi] (else an error at `where`).
  // Compared as that float: a bound written in a file (1e-7) is a double a little off the float
  // bound, and must be accepted.
  static float float_in_range(double d, float lo, float hi, const std::string& where) {
    const float f = float(d);
    if (!(f >= lo && f <= hi))
      fail(where, "must be in [" + fmt(lo) + ", " + fmt(hi) + "], was " + fmt(d));
    return f;
  }
  const json& j_;
  std::string path_;
  std::vector<std::string> known_;
};

/// "line L, column C" of the 1-based byte position `byte` (what nlohmann reports) in `text`.
inline std::string line_column(const std::string& text, std::size_t byte) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}

/// `text` in single quotes for a message; a long one (a number of thousands of digits, a value
/// pasted by mistake) is cut to its first 32 characters and its length.
inline std::string quote(std::string_view text) {
  constexpr std::size_t kShown = 32;
  std::string out = "'";
  if (text.size() <= 2 * kShown) return out.append(text).append("'");
  return out.append(text.substr(0, kShown))
      .append("...' (")
      .append(std::to_string(text.size()))
      .append(" characters)");
}

/// The deepest nesting of arrays and objects in any JSON Kaskad reads: scene, material,
/// playback and glTF files, `--set` values and the blocks inside them. Scenes nest about 6 deep
/// and glTF about 10; the limit keeps the code that walks a value recursively (copying,
/// comparing, writing it) far from the end of the stack.
inline constexpr int kMaxDepth = 256;

/// Refuses `text` when its arrays and objects nest deeper than kMaxDepth, naming the line and
/// column of the first bracket too deep; brackets inside strings do not count. One linear scan
/// that needs no valid JSON (syntax errors are the parser's to report), so it runs first.
inline Status check_depth(std::string_view text, const std::string& file) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (!escaped && c == '"') in_string = false;
      escaped = !escaped && c == '\\';
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kMaxDepth)
        return Error{file, line_column(std::string(text.substr(0, i + 1)), i + 1),
                     "arrays and objects nested deeper than " + std::to_string(kMaxDepth) +
                         " levels (the limit of every JSON Kaskad reads)"};
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return {};
}

/// nlohmann's message without its "[json.exception.xxx.N] " prefix and the "parse error at line
/// L, column C: " that our Error::where already gives; bytes that are not printable ASCII (the
/// message quotes the input) are shown as \xNN.
inline std::string json_message(const std::exception& e) {
  std::string msg = e.what();
  if (msg.rfind("[json.exception", 0) == 0)
    if (auto p = msg.find("] "); p != std::string::npos) msg = msg.substr(p + 2);
  if (msg.rfind("parse error at line ", 0) == 0)
    if (auto p = msg.find(": "); p != std::string::npos) msg = "parse error: " + msg.substr(p + 2);
  std::string out;
  for (const char c : msg) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      static const char* hex = "0123456789ABCDEF";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  // Quoted input (a number of thousands of digits) is cut as quote() cuts it.
  std::string cut;
  for (std::size_t at = 0; at < out.size();) {
    const std::size_t open = out.find('\'', at);
    const std::size_t close = open == std::string::npos ? open : out.find('\'', open + 1);
    if (close == std::string::npos) {
      cut += out.substr(at);
      break;
    }
    cut += out.substr(at, open - at) + quote(std::string_view(out).substr(open + 1, close - open - 1));
    at = close + 1;
  }
  return cut;
}

/// A SAX consumer that only remembers where the parser gave up: nlohmann reports number
/// overflows (1e999) as out_of_range without a position, but tells a SAX consumer the offset.
struct ErrorLocator {
  std::size_t byte = 0;
  bool null() { return true; }
  bool boolean(bool) { return true; }
  bool number_integer(json::number_integer_t) { return true; }
  bool number_unsigned(json::number_unsigned_t) { return true; }
  bool number_float(json::number_float_t, const json::string_t&) { return true; }
  bool string(json::string_t&) { return true; }
  bool binary(json::binary_t&) { return true; }
  bool start_object(std::size_t) { return true; }
  bool key(json::string_t&) { return true; }
  bool end_object() { return true; }
  bool start_array(std::size_t) { return true; }
  bool end_array() { return true; }
  bool parse_error(std::size_t position, const std::string&, const json::exception&) {
    byte = position;
    return false;
  }
};

/// A SAX consumer that finds the first key given twice in one object (the parser would keep the
/// last and drop the other without a word), as the JSON pointer of the second one.
struct DuplicateKeyFinder {
  struct Level {
    bool object = false;
    std::vector<std::string> keys;  // objects: keys so far
    std::size_t index = 0;          // arrays: elements so far
  };
  std::vector<Level> levels;
  std::string duplicate, pointer;

  void element() {
    if (!levels.empty() && !levels.back().object) ++levels.back().index;
  }
  bool scalar() {
    element();
    return true;
  }
  bool null() { return scalar(); }
  bool boolean(bool) { return scalar(); }
  bool number_integer(json::number_integer_t) { return scalar(); }
  bool number_unsigned(json::number_unsigned_t) { return scalar(); }
  bool number_float(json::number_float_t, const json::string_t&) { return scalar(); }
  bool string(json::string_t&) { return scalar(); }
  bool binary(json::binary_t&) { return scalar(); }
  bool start_object(std::size_t) {
    element();
    levels.push_back({true, {}, 0});
    return true;
  }
  bool start_array(std::size_t) {
    element();
    levels.push_back({false, {}, 0});
    return true;
  }
  bool end_object() { return end(); }
  bool end_array() { return end(); }
  bool end() {
    levels.pop_back();
    return true;
  }
  bool key(json::string_t& k) {
    std::vector<std::string>& keys = levels.back().keys;
    if (std::find(keys.begin(), keys.end(), k) == keys.end()) {
      keys.push_back(k);
      return true;
    }
    duplicate = k;
    keys.push_back(k);  // the last key of each object level names it in the pointer
    for (const Level& l : levels) {
      pointer += '/';
      if (!l.object) {
        pointer += std::to_string(l.index - 1);
        continue;
      }
      for (char c : l.keys.back()) pointer += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    }
    return false;  // the first one is enough
  }
  bool parse_error(std::size_t, const std::string&, const json::exception&) { return false; }
};

/// Parses JSON text read from `file` (used in messages). Nesting deeper than kMaxDepth and every
/// error nlohmann can raise (syntax, number overflow, invalid UTF-8, ...) become a content error
/// with line and column; a key given twice in one object, an error at its JSON pointer.
inline Result<json> parse_json_text(const std::string& text, const std::string& file) {
  KASKAD_TRY(check_depth(text, file));
  try {
    json doc = json::parse(text, nullptr, true, /*ignore_comments=*/false);
    DuplicateKeyFinder keys;
    json::sax_parse(text, &keys);
    if (!keys.duplicate.empty())
      return Error{file, keys.pointer,
                   "the key '" + keys.duplicate +
                       "' is given twice in this object (only one would count); give it once"};
    return doc;
  } catch (const json::parse_error& e) {
    return Error{file, line_column(text, e.byte), "malformed JSON: " + json_message(e)};
  } catch (const json::exception& e) {
    ErrorLocator locator;
    std::string where;
    try {
      json::sax_parse(text, &locator);
      if (locator.byte > 0) where = line_column(text, locator.byte);
    } catch (const std::exception&) {
      // only used to find the place; the message below stands without it
    }
    return Error{file, where, "invalid JSON: " + json_message(e)};
  } catch (const std::bad_alloc&) {
    return Error{file, "", "out of memory while parsing JSON"};
  } catch (const std::exception& e) {
    return Error{file, "", std::string("cannot parse JSON: ") + e.what()};
  }
}

/// Parses a JSON file (at most 256 MiB); a missing, empty or unreadable file, a folder, and every
/// JSON error give the file and, for errors inside it, the line and column.
inline Result<json> parse_json_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec) && std::filesystem::file_size(file, ec) == 0 && !ec)
    return parse_json_text({}, file.string());  // "malformed JSON" at line 1, column 1
  auto bytes = read_file_bytes(file, std::uintmax_t(256) << 20);
  if (!bytes) {
    Error e = bytes.error();
    e.message = "cannot open: " + e.message;
    return e;
  }
  return parse_json_text(std::string(bytes->begin(), bytes->end()), file.string());
}

}  // namespace kaskad::json_reader
