#include "runtime/cli/options.h"

#include <cctype>
#include <cstdio>
#include <optional>

#include "runtime/core/log.h"

namespace kaskad::cli {
namespace {

/// `text` as an integer in [lo, hi], or nothing (not a number, trailing characters, out of range).
std::optional<int> integer_in(const std::string& text, long lo, long hi) {
  if (text.empty()) return std::nullopt;
  try {
    std::size_t used = 0;
    const long n = std::stol(text, &used);
    if (used != text.size() || n < lo || n > hi) return std::nullopt;
    return int(n);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

/// Splits "AsepB" at the first `sep`; false when there is none.
bool split_at(const std::string& v, char sep, std::string& a, std::string& b) {
  const auto at = v.find(sep);
  if (at == std::string::npos) return false;
  a = v.substr(0, at);
  b = v.substr(at + 1);
  return true;
}

// The checks return "" for a good value, else the message CLI11 prints after "--option: ".
// Change together with the parsers below them, which rely on the value having passed.

std::string check_size(const std::string& v, int lo, int hi) {
  std::string w, h;
  if (!split_at(v, 'x', w, h)) return "expects WxH, e.g. 1280x720, got '" + v + "'";
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!integer_in(w, lo, hi)) return "the width must be an integer in " + range + ", got '" + v + "'";
  if (!integer_in(h, lo, hi)) return "the height must be an integer in " + range + ", got '" + v + "'";
  return {};
}

constexpr int kMaxShards = 100000;

std::string check_shard(const std::string& v) {
  std::string i, n;
  const auto count = split_at(v, '/', i, n) ? integer_in(n, 1, kMaxShards) : std::nullopt;
  if (!count || !integer_in(i, 0, *count - 1))
    return "expects i/n with 0 <= i < n <= " + std::to_string(kMaxShards) + ", e.g. 0/4, got '" +
           v + "'";
  return {};
}

}  // namespace

int print_usage_error(const std::string& command, const std::string& message) {
  const std::string who = command.empty() ? "kaskad" : "kaskad " + command;
  std::fprintf(stderr, "%s: %s\n(run `%s --help` for usage)\n", who.c_str(), message.c_str(),
               who.c_str());
  return 2;
}

const CLI::Validator& not_an_option() {
  static const CLI::Validator check(
      [](std::string& v) -> std::string {
        if (v.size() > 1 && v[0] == '-' && !std::isdigit(static_cast<unsigned char>(v[1])))
          return "needs a value, got the option '" + v + "'";
        return {};
      },
      "");
  return check;
}

CLI::Option* add_size_option(CLI::App& cmd, int& width, int& height, int lo, int hi,
                             const std::string& description) {
  CLI::Option* o = cmd.add_option_function<std::string>(
      "--size",
      [&width, &height](const std::string& v) {
        std::string w, h;
        split_at(v, 'x', w, h);
        width = *integer_in(w, 0, 1 << 30);
        height = *integer_in(h, 0, 1 << 30);
      },
      description + " (W and H in [" + std::to_string(lo) + ", " + std::to_string(hi) + "])");
  o->type_name("WxH")->allow_extra_args(false);
  o->check(CLI::Validator([lo, hi](std::string& v) { return check_size(v, lo, hi); }, ""));
  return o;
}

CLI::Option* add_shard_option(CLI::App& cmd, int& index, int& count,
                              const std::string& description) {
  CLI::Option* o = cmd.add_option_function<std::string>(
      "--shard",
      [&index, &count](const std::string& v) {
        std::string i, n;
        split_at(v, '/', i, n);
        index = *integer_in(i, 0, kMaxShards);
        count = *integer_in(n, 1, kMaxShards);
      },
      description);
  o->type_name("i/n")->allow_extra_args(false);
  o->check(CLI::Validator([](std::string& v) { return check_shard(v); }, ""));
  return o;
}

CLI::Option* add_jobs_option(CLI::App& cmd, int& jobs, const std::string& description) {
  return cmd.add_option("--jobs", jobs, description)
      ->type_name("N")
      ->allow_extra_args(false)
      ->check(CLI::Range(1, 256));
}

CLI::Option* add_frames_option(CLI::App& cmd, int& frames, const std::string& description) {
  return cmd.add_option("--frames", frames, description)
      ->type_name("N")
      ->allow_extra_args(false)
      ->check(CLI::Range(1, 100000));
}

void add_window_flags(CLI::App& cmd, bool& headless) {
  // Called as they are parsed, so that of `--window --headless` the last one counts.
  cmd.add_flag_callback("--headless", [&headless] { headless = true; },
                        "never open a window (default when there is no display)")
      ->trigger_on_parse();
  cmd.add_flag_callback("--window", [&headless] { headless = false; },
                        "open a window even where --headless would be the default")
      ->trigger_on_parse();
}

void add_verbose_flag(CLI::App& cmd) {
  cmd.add_flag_callback("-v,--verbose", [] { log::set_level(log::Level::debug); },
                        "debug logging (GL debug messages of every severity)");
}

}  // namespace kaskad::cli
