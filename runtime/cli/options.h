// The command line's shared pieces (CLI11): the options several commands take, declared once so
// that each reads its value, checks its range and words its help and its errors the same way
// everywhere, and the shape of a command (Command) that main.cpp's table lists.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace kaskad::cli {

/// Runs a command once its options are parsed; returns the exit status (0 success, 1 a content
/// error, 2 a usage error).
using RunCommand = std::function<int()>;

/// One `kaskad COMMAND`. `add` declares the command's options on its subcommand `cmd` (each
/// binding into an options struct the returned function owns) and returns the function that runs
/// it. Adding a command is one such function and one row in main.cpp's table, e.g.
///   RunCommand add_check_command(CLI::App& cmd) {
///     auto o = std::make_shared<CheckOptions>();
///     add_value_option(cmd, "-o,--output", o->output, "where to write the report");
///     return [o] { return run_check(*o); };
///   }
struct Command {
  const char* name;
  const char* summary;  ///< one line for `kaskad --help`; `kaskad NAME --help` lists the options
  RunCommand (*add)(CLI::App& cmd);
};

/// A usage error found after parsing (two options that do not go together, a missing input):
/// printed like a parse error, exit status 2.
struct UsageError : CLI::ParseError {
  explicit UsageError(const std::string& message)
      : CLI::ParseError("UsageError", message, CLI::ExitCodes::ValidationError) {}
};

/// Prints a usage error of `command` ("render"; empty: the top level) as one line, then where the
/// help is: "kaskad render: MESSAGE" / "(run `kaskad render --help` for usage)". Returns 2.
int print_usage_error(const std::string& command, const std::string& message);

/// The check every option with a value gets: its value is never the next option (`--set -o x.png`
/// names no value; "-5" is a value, left to the option's own check; a file named -x is ./-x).
const CLI::Validator& not_an_option();

/// An option with one value (a string, a path, a repeatable list of strings: each occurrence
/// takes one), checked by not_an_option().
template <class T>
CLI::Option* add_value_option(CLI::App& cmd, const std::string& name, T& into,
                              const std::string& description) {
  return cmd.add_option(name, into, description)->allow_extra_args(false)->check(not_an_option());
}

/// What an output option names, for add_output_option's check.
enum class OutputKind {
  file,    ///< a file: its folder exists and takes new files; not a folder, not a device
  image,   ///< a file as above, in an image format kaskad writes (by its extension)
  folder,  ///< a folder that takes new files, or one the command makes: its parent must exist
  faces,   ///< envmap --faces: a pattern with one * (six images) or a folder as above
};

/// The check of every output option, done as the command line is parsed, so before any work:
/// a path that cannot be written (runtime/core/atomic_file.h's checks) is a usage error naming
/// the option and the path ("--sphere: /no/dir/x.png: cannot write here: folder '/no/dir' does
/// not exist ..."), exit status 2. Nothing is made here; a folder is made by the command.
std::string output_problem(const std::string& path, OutputKind kind);

/// An option naming an output (add_value_option, checked by output_problem()).
template <class T>
CLI::Option* add_output_option(CLI::App& cmd, const std::string& name, T& into, OutputKind kind,
                               const std::string& description) {
  return add_value_option(cmd, name, into, description)
      ->check(CLI::Validator([kind](std::string& v) { return output_problem(v, kind); }, ""));
}

/// An option with one integer value in [lo, hi] (its help says the range once, as "N in [lo, hi]").
CLI::Option* add_integer_option(CLI::App& cmd, const std::string& name, int& into, int lo, int hi,
                                const std::string& description);

/// An option with one finite number in [lo, hi] ("S in [lo, hi]").
CLI::Option* add_number_option(CLI::App& cmd, const std::string& name, double& into, double lo,
                               double hi, const std::string& description);

/// `--size WxH`: width and height in pixels, each in [lo, hi].
CLI::Option* add_size_option(CLI::App& cmd, int& width, int& height, int lo, int hi,
                             const std::string& description);

/// `--shard i/n`: this process takes part i of n (0 <= i < n <= 100000).
CLI::Option* add_shard_option(CLI::App& cmd, int& index, int& count, const std::string& description);

/// `--jobs N`: N worker processes, in [1, 256].
CLI::Option* add_jobs_option(CLI::App& cmd, int& jobs, const std::string& description);

/// `--frames N`: a frame count in [1, 100000].
CLI::Option* add_frames_option(CLI::App& cmd, int& frames, const std::string& description);

/// `--headless` and `--window`, the last given wins; `headless` keeps its value when neither is.
void add_window_flags(CLI::App& cmd, bool& headless);

/// `-v, --verbose`: debug logging (GL debug messages of every severity).
void add_verbose_flag(CLI::App& cmd);

}  // namespace kaskad::cli
