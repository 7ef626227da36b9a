// Minimal levelled logging to stderr. Tests can count errors (GL errors are bugs: KHR_debug output
// of type ERROR goes through log_error and is counted, and tests fail when the count is non-zero).
#pragma once

#include <cstdarg>
#include <string>

namespace kaskad::log {

enum class Level { debug, info, warn, error };

/// Messages below this level are dropped. Default: info.
void set_level(Level level);
Level level();

void debug(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void info(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void warn(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void error(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
/// warn(), but each distinct message only the first time: for conditions found again every
/// frame (a parent cycle, too many lights). Prefixed with the context (set_context()).
void warn_once(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

/// What warn_once() messages are about, e.g. the scene file being played ("" for none). The
/// player sets it when it loads a scene; the systems know entities, not files.
void set_context(const std::string& context);

/// Number of error-level messages logged since start (or the last reset).
int error_count();
void reset_error_count();

}  // namespace kaskad::log
