// Outputs are written atomically: every file Kaskad writes (images, AOVs, CSV, charts, scene
// saves, probe dumps, the shader cache) goes to a temporary file in the target's own folder,
// is checked (every write() complete, fsync), and only then renamed over the target. On any
// failure the temporary file is removed and the previous file is left byte-identical. An output
// named by a symbolic link replaces the file the link points to; the link stays.
// No folder is ever created here: callers that create one do it because the user named it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad {

/// Checks, without leaving anything behind, that `path` can be written as an output file: it is
/// not a folder and not a special file (a device, a pipe), its folder exists and a file can be
/// created in it (tried for real: root passes permission checks, but not on /proc or a
/// read-only mount). Errors name the path and the problem.
Status check_output_path(const std::filesystem::path& path);

/// Checks that `dir` is an existing folder in which files can be created.
Status check_output_folder(const std::filesystem::path& dir);

/// For an output folder the caller makes when it is missing (one level, the one the user
/// named): `dir` is a folder that takes new files, or it does not exist and its parent is one.
/// Makes nothing.
Status check_output_folder_to_make(const std::filesystem::path& dir);

/// Writes `size` bytes atomically to `path` (see the top of this file). Errors name the path,
/// how many bytes were written and why it stopped (e.g. "File too large" under `ulimit -f`).
Status write_file_atomic(const std::filesystem::path& path, const void* data, std::size_t size);
inline Status write_file_atomic(const std::filesystem::path& path, const std::string& text) {
  return write_file_atomic(path, text.data(), text.size());
}
inline Status write_file_atomic(const std::filesystem::path& path,
                                const std::vector<std::uint8_t>& bytes) {
  return write_file_atomic(path, bytes.data(), bytes.size());
}

/// For writers that can only write to a file name themselves (a library that opens the file):
/// a fresh temporary file beside `target`, with the same extension (libraries pick the format by
/// it). commit() checks it is non-empty, syncs it and renames it over the target; the destructor
/// removes it unless committed.
class TempFile {
 public:
  static Result<TempFile> create(const std::filesystem::path& target);
  TempFile(TempFile&& other) noexcept;
  TempFile& operator=(TempFile&&) = delete;
  TempFile(const TempFile&) = delete;
  ~TempFile();

  const std::filesystem::path& path() const { return temp_; }
  Status commit();

 private:
  TempFile(std::filesystem::path target, std::filesystem::path temp)
      : target_(std::move(target)), temp_(std::move(temp)) {}
  std::filesystem::path target_;
  std::filesystem::path temp_;
  bool done_ = false;
};

}  // namespace kaskad
