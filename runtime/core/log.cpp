#include "runtime/core/log.h"

#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

namespace kaskad::log {
namespace {
std::atomic<Level> g_level{Level::info};
std::atomic<int> g_errors{0};

void vlog(Level lvl, const char* tag, const char* fmt, va_list args) {
  if (lvl < g_level.load()) return;
  // The whole line is formatted first and written with one call, so that lines logged from
  // several threads do not interleave.
  va_list measure;
  va_copy(measure, args);
  const int body = std::vsnprintf(nullptr, 0, fmt, measure);
  va_end(measure);
  if (body < 0) return;
  std::string line = "[kaskad " + std::string(tag) + "] ";
  const std::size_t prefix = line.size();
  line.resize(prefix + std::size_t(body) + 1);
  std::vsnprintf(line.data() + prefix, std::size_t(body) + 1, fmt, args);
  line.back() = '\n';
  std::fwrite(line.data(), 1, line.size(), stderr);
}
}  // namespace

void set_level(Level lvl) { g_level = lvl; }
Level level() { return g_level; }

#define KASKAD_LOG_FN(name, lvl, tag) \
  void name(const char* fmt, ...) {   \
    va_list args;                     \
    va_start(args, fmt);              \
    vlog(lvl, tag, fmt, args);        \
    va_end(args);                     \
  }
KASKAD_LOG_FN(debug, Level::debug, "debug")
KASKAD_LOG_FN(info, Level::info, "info")
KASKAD_LOG_FN(warn, Level::warn, "warn")
#undef KASKAD_LOG_FN

void error(const char* fmt, ...) {
  ++g_errors;
  va_list args;
  va_start(args, fmt);
  vlog(Level::error, "error", fmt, args);
  va_end(args);
}

namespace {
std::mutex g_once_mutex;
std::set<std::string> g_said;  // warn_once() messages already printed
std::string g_context;
}  // namespace

void set_context(const std::string& context) {
  const std::lock_guard<std::mutex> lock(g_once_mutex);
  g_context = context;
}

void warn_once(const char* fmt, ...) {
  char buf[1024];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  std::string message;
  {
    const std::lock_guard<std::mutex> lock(g_once_mutex);
    // A message that already names the context (a glTF opened directly is its own scene file)
    // is not prefixed twice.
    const bool named = std::string_view(buf).starts_with(g_context + ":");
    message = g_context.empty() || named ? std::string(buf) : g_context + ": " + buf;
    if (!g_said.insert(message).second) return;
  }
  warn("%s", message.c_str());
}

int error_count() { return g_errors; }
void reset_error_count() { g_errors = 0; }

}  // namespace kaskad::log
