// Whole-file reads with messages for the common ways they fail.
#pragma once

#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad {

/// The folder a file is in: its parent path, or "." for a bare name.
inline std::filesystem::path folder_of(const std::filesystem::path& path) {
  return path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
}

/// A file's extension as path::extension() gives it (".glb": with the dot; empty without one),
/// in ASCII lower case: how file types are told apart by name.
inline std::string lowercase_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// Why `path`, which exists and is not a folder, must not be opened for reading: a named pipe, a
/// device or a socket (opening a FIFO waits for a writer, forever). "" for a regular file (links
/// followed) and for paths that are missing or folders, which each reader words itself.
inline std::string special_file_error(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status) || std::filesystem::is_directory(status) ||
      std::filesystem::is_regular_file(status))
    return {};
  const char* kind = std::filesystem::is_fifo(status)           ? "a named pipe (FIFO)"
                     : std::filesystem::is_character_file(status) ? "a character device"
                     : std::filesystem::is_block_file(status)     ? "a block device"
                     : std::filesystem::is_socket(status)         ? "a socket"
                                                                  : "a special file";
  return std::string("not a regular file but ") + kind + "; kaskad reads only regular files";
}

/// The bytes of a file. Errors name the file: missing, a directory, not a regular file, empty,
/// larger than `max_bytes`, unreadable, or shorter than its size said.
inline Result<std::vector<std::uint8_t>> read_file_bytes(const std::filesystem::path& path,
                                                         std::uintmax_t max_bytes) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) return Error{name, "", "file not found"};
  if (std::filesystem::is_directory(status)) return Error{name, "", "is a directory, not a file"};
  if (std::string why = special_file_error(path); !why.empty()) return Error{name, "", why};
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return Error{name, "", "cannot read file size: " + ec.message()};
  if (size == 0) return Error{name, "", "empty file (0 bytes)"};
  if (size > max_bytes)
    return Error{name, "", "file larger than " + std::to_string(max_bytes >> 20) + " MiB"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{name, "", "cannot open file for reading"};
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()));
  if (std::size_t(in.gcount()) != bytes.size()) return Error{name, "", "short read"};
  return bytes;
}

}  // namespace kaskad
