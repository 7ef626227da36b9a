// GLSL program building from files under content/shaders/. Sources may `#include "file.glsl"`;
// every included file gets its own GLSL source-string number via `#line`, so compiler messages are
// mapped back to the original file and line instead of the concatenated string.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"

namespace kaskad::gpu {

/// A preprocessed stage: the text handed to GL plus the files its `#line` numbers refer to.
struct ShaderSource {
  std::string text;
  std::vector<std::string> files;  ///< index = GLSL source-string number used in #line
};

/// Reads `path` (relative to `root`), expands includes (depth <= 16, no cycles) and prepends
/// `#version 450 core` and one `#define NAME VALUE` per entry of `defines`.
Result<ShaderSource> preprocess_shader(const std::filesystem::path& root,
                                       const std::string& path,
                                       const std::vector<std::pair<std::string, std::string>>& defines);

/// Rewrites a GL info log so "0:12(5): error: ..." reads "forward.frag:12(5): error: ...".
std::string map_shader_log(const std::string& log, const std::vector<std::string>& files);

/// Compiles and links a vertex + fragment program. Errors carry the mapped compiler/linker log.
/// `retrievable`: ask the driver to keep the binary for program_binary().
Result<Program> build_program(const ShaderSource& vertex, const ShaderSource& fragment,
                              bool retrievable = false);

/// Compiles and links a compute program (the deform pass's).
Result<Program> build_compute_program(const ShaderSource& compute, bool retrievable = false);

/// A linked program's binary (GL_ARB_get_program_binary); empty when the driver gives none.
std::vector<std::uint8_t> program_binary(const Program& program, GLenum& format);

/// A program from a binary; an Error when the driver rejects it (e.g. after a driver update).
Result<Program> program_from_binary(GLenum format, const std::vector<std::uint8_t>& binary);

}  // namespace kaskad::gpu
