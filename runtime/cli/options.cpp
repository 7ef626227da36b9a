#include "runtime/cli/options.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <optional>

#include "runtime/assets/image_io.h"
#include "runtime/core/atomic_file.h"
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

/// A pair option's value ("1280x720", "0/4"), read once: the validator reports `error`, the
/// option's function stores `first` and `second` (only called once the validator passed).
struct Pair {
  std::string error;  ///< "" for a good value, else the message CLI11 prints after "--option: "
  int first = 0, second = 0;
};

Pair read_size(const std::string& v, int lo, int hi) {
  std::string w, h;
  if (!split_at(v, 'x', w, h)) return {"expects WxH, e.g. 1280x720, got '" + v + "'"};
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const auto width = integer_in(w, lo, hi), height = integer_in(h, lo, hi);
  if (!width) return {"the width must be an integer in " + range + ", got '" + v + "'"};
  if (!height) return {"the height must be an integer in " + range + ", got '" + v + "'"};
  return {"", *width, *height};
}

constexpr int kMaxShards = 100000;

Pair read_shard(const std::string& v) {
  std::string i, n;
  const auto count = split_at(v, '/', i, n) ? integer_in(n, 1, kMaxShards) : std::nullopt;
  const auto index = count ? integer_in(i, 0, *count - 1) : std::nullopt;
  if (!index)
    return {"expects i/n with 0 <= i < n <= " + std::to_string(kMaxShards) + ", e.g. 0/4, got '" +
            v + "'"};
  return {"", *index, *count};
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

std::string output_problem(const std::string& path, OutputKind kind) {
  Status st;
  switch (kind) {
    case OutputKind::file:
      st = check_output_path(path);
      break;
    case OutputKind::image:
      st = check_image_output(path);
      break;
    case OutputKind::folder:
      st = check_output_folder_to_make(path);
      break;
    case OutputKind::faces:
      if (const auto star = path.find('*'); star != std::string::npos) {
        // The six files differ only in the face name: one stands for all (its folder, format).
        std::string px = path;
        px.replace(star, 1, "px");
        st = check_image_output(px);
      } else {
        st = check_output_folder_to_make(path);
      }
      break;
  }
  return st ? std::string() : st.error().to_string();
}

CLI::Option* add_size_option(CLI::App& cmd, int& width, int& height, int lo, int hi,
                             const std::string& description) {
  CLI::Option* o = cmd.add_option_function<std::string>(
      "--size",
      [&width, &height, lo, hi](const std::string& v) {
        const Pair size = read_size(v, lo, hi);
        width = size.first;
        height = size.second;
      },
      description + "; W and H in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  o->type_name("WxH")->allow_extra_args(false);
  o->check(CLI::Validator([lo, hi](std::string& v) { return read_size(v, lo, hi).error; }, ""));
  return o;
}

CLI::Option* add_shard_option(CLI::App& cmd, int& index, int& count,
                              const std::string& description) {
  CLI::Option* o = cmd.add_option_function<std::string>(
      "--shard",
      [&index, &count](const std::string& v) {
        const Pair shard = read_shard(v);
        index = shard.first;
        count = shard.second;
      },
      description);
  o->type_name("i/n")->allow_extra_args(false);
  o->check(CLI::Validator([](std::string& v) { return read_shard(v).error; }, ""));
  return o;
}

CLI::Option* add_integer_option(CLI::App& cmd, const std::string& name, int& into, int lo, int hi,
                                const std::string& description) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return cmd.add_option(name, into, description + "; N in " + range)
      ->type_name("N")
      ->allow_extra_args(false)
      ->check(CLI::Range(lo, hi).description(""));
}

CLI::Option* add_number_option(CLI::App& cmd, const std::string& name, double& into, double lo,
                               double hi, const std::string& description) {
  auto text = [](double v) {
    std::string s = std::to_string(v);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  };
  const std::string range = "[" + text(lo) + ", " + text(hi) + "]";
  return cmd.add_option(name, into, description + "; S in " + range)
      ->type_name("S")
      ->allow_extra_args(false)
      ->check(CLI::Validator(
          [lo, hi, range](std::string& v) -> std::string {
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(x))
              return "'" + v + "' is not a number";
            if (x < lo || x > hi) return "'" + v + "' is outside " + range;
            return "";
          },
          ""));
}

CLI::Option* add_jobs_option(CLI::App& cmd, int& jobs, const std::string& description) {
  return add_integer_option(cmd, "--jobs", jobs, 1, 256, description);
}

CLI::Option* add_frames_option(CLI::App& cmd, int& frames, const std::string& description) {
  return add_integer_option(cmd, "--frames", frames, 1, 100000, description);
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
