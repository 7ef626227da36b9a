// Content errors: everything that comes from files (JSON, glTF, Draco, images, shaders) is reported
// through Result<T>, shown to the user and never aborts (STYLE.md 10). API misuse uses
// KASKAD_CHECK (precondition, names the function and value); internal invariants use assert().
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>

namespace kaskad {

/// A content error: which file, where in it (a JSON path, a glTF accessor, a line), and what is wrong.
struct Error {
  std::string file;     ///< file the problem is in; empty when not file-related
  std::string where;    ///< place inside the file, e.g. "/entities/3/light/type" or "line 12"
  std::string message;  ///< what is wrong, in words a content author understands

  /// "file: where: message", leaving out empty parts.
  std::string to_string() const {
    std::string s;
    if (!file.empty()) s += file + ": ";
    if (!where.empty()) s += where + ": ";
    return s + message;
  }
};

/// Either a value or an Error. Deliberately small; C++23's std::expected is not available in C++20.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  Result(Error error) : v_(std::move(error)) {}

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() { return value(); }

  const Error& error() const { return std::get<1>(v_); }

 private:
  std::variant<T, Error> v_;
};

/// Result of an operation that produces nothing but may fail.
template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : error_(std::move(error)), ok_(false) {}
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const { return error_; }

 private:
  Error error_;
  bool ok_ = true;
};

using Status = Result<void>;

[[noreturn]] inline void precondition_failed(const char* function, const std::string& message) {
  std::fprintf(stderr, "kaskad: precondition failed in %s: %s\n", function, message.c_str());
  std::abort();
}

}  // namespace kaskad

/// Precondition check for API misuse; active in every build type. The message names the value.
#define KASKAD_CHECK(cond, message)                                              \
  do {                                                                           \
    if (!(cond)) ::kaskad::precondition_failed(__func__, std::string(message));  \
  } while (false)

/// Propagates an error from an expression returning Status.
#define KASKAD_TRY(expr)                          \
  do {                                            \
    if (auto _st = (expr); !_st.ok()) return _st.error(); \
  } while (false)
