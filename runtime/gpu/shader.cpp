#include "runtime/gpu/shader.h"

#include <algorithm>
#include <initializer_list>
#include <fstream>
#include <regex>
#include <sstream>

#include "runtime/core/file_io.h"

namespace kaskad::gpu {
namespace {

Result<std::string> read_text(const std::filesystem::path& file) {
  if (std::string why = special_file_error(file); !why.empty()) return Error{file.string(), "", why};
  std::ifstream in(file, std::ios::binary);
  if (!in) return Error{file.string(), "", "cannot open shader file"};
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Status expand(const std::filesystem::path& root, const std::string& rel, int depth,
              ShaderSource& out, std::vector<std::string>& stack) {
  if (depth > 16) return Error{rel, "", "#include nesting deeper than 16"};
  for (const auto& s : stack)
    if (s == rel) return Error{rel, "", "#include cycle"};
  auto text = read_text(root / rel);
  if (!text) return Error{(root / rel).string(), "", text.error().message};
  const int file_index = int(out.files.size());
  out.files.push_back(rel);
  stack.push_back(rel);
  out.text += "#line 1 " + std::to_string(file_index) + "\n";
  std::istringstream lines(*text);
  std::string line;
  int line_no = 0;
  static const std::regex include_re(R"(^\s*#\s*include\s+\"([^\"]+)\"\s*$)");
  while (std::getline(lines, line)) {
    ++line_no;
    std::smatch m;
    if (std::regex_match(line, m, include_re)) {
      const std::string inc = (std::filesystem::path(rel).parent_path() / m[1].str()).string();
      if (auto st = expand(root, inc, depth + 1, out, stack); !st) {
        Error e = st.error();
        if (e.where.empty()) e.where = rel + ":" + std::to_string(line_no);
        return e;
      }
      out.text += "#line " + std::to_string(line_no + 1) + " " + std::to_string(file_index) + "\n";
    } else {
      out.text += line;
      out.text += '\n';
    }
  }
  stack.pop_back();
  return {};
}

Result<Shader> compile_stage(GLenum stage, const ShaderSource& src) {
  Shader shader(glCreateShader(stage));
  const char* text = src.text.c_str();
  glShaderSource(shader.id(), 1, &text, nullptr);
  glCompileShader(shader.id());
  GLint ok = 0;
  glGetShaderiv(shader.id(), GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(shader.id(), GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    glGetShaderInfoLog(shader.id(), len, nullptr, log.data());
    return Error{src.files.empty() ? "" : src.files[0], "compile",
                 map_shader_log(log.c_str(), src.files)};
  }
  return shader;
}

}  // namespace

Result<ShaderSource> preprocess_shader(
    const std::filesystem::path& root, const std::string& path,
    const std::vector<std::pair<std::string, std::string>>& defines) {
  ShaderSource out;
  out.text = "#version 450 core\n";
  for (const auto& [name, value] : defines) out.text += "#define " + name + " " + value + "\n";
  std::vector<std::string> stack;
  if (auto st = expand(root, path, 0, out, stack); !st) return st.error();
  return out;
}

std::string map_shader_log(const std::string& log, const std::vector<std::string>& files) {
  // Mesa writes "0:12(5): error: ...", NVIDIA "0(12) : error ...": both start with the string number.
  static const std::regex mesa_re(R"((^|\n)(\d+):(\d+)\()");
  static const std::regex nv_re(R"((^|\n)(\d+)\((\d+)\))");
  auto rewrite = [&](const std::string& in, const std::regex& re, bool mesa) {
    std::string out;
    auto begin = std::sregex_iterator(in.begin(), in.end(), re);
    std::size_t last = 0;
    for (auto it = begin; it != std::sregex_iterator(); ++it) {
      const auto& m = *it;
      out.append(in, last, std::size_t(m.position(0)) - last);
      const std::size_t idx = std::stoul(m[2].str());
      const std::string name = idx < files.size() ? files[idx] : m[2].str();
      out += m[1].str() + name + ":" + m[3].str() + (mesa ? "(" : "");
      last = std::size_t(m.position(0) + m.length(0));
    }
    out.append(in, last, std::string::npos);
    return out;
  };
  return rewrite(rewrite(log, mesa_re, true), nv_re, false);
}

namespace {

/// Compiles each stage and links them into one program.
Result<Program> link_stages(std::initializer_list<std::pair<GLenum, const ShaderSource*>> stages,
                            bool retrievable) {
  std::vector<Shader> shaders;
  for (const auto& [type, source] : stages) {
    auto shader = compile_stage(type, *source);
    if (!shader) return shader.error();
    shaders.push_back(std::move(shader.value()));
  }
  Program program(glCreateProgram());
  for (const Shader& sh : shaders) glAttachShader(program.id(), sh.id());
  if (retrievable) glProgramParameteri(program.id(), GL_PROGRAM_BINARY_RETRIEVABLE_HINT, GL_TRUE);
  glLinkProgram(program.id());
  for (const Shader& sh : shaders) glDetachShader(program.id(), sh.id());
  GLint ok = 0;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    glGetProgramInfoLog(program.id(), len, nullptr, log.data());
    const ShaderSource& first = *stages.begin()->second;
    return Error{first.files.empty() ? "" : first.files[0], "link",
                 map_shader_log(log.c_str(), first.files)};
  }
  return program;
}

}  // namespace

Result<Program> build_program(const ShaderSource& vertex, const ShaderSource& fragment,
                              bool retrievable) {
  return link_stages({{GL_VERTEX_SHADER, &vertex}, {GL_FRAGMENT_SHADER, &fragment}}, retrievable);
}

Result<Program> build_compute_program(const ShaderSource& compute, bool retrievable) {
  return link_stages({{GL_COMPUTE_SHADER, &compute}}, retrievable);
}

std::vector<std::uint8_t> program_binary(const Program& program, GLenum& format) {
  GLint length = 0;
  glGetProgramiv(program.id(), GL_PROGRAM_BINARY_LENGTH, &length);
  std::vector<std::uint8_t> out(std::size_t(std::max(length, 0)));
  if (out.empty()) return out;
  GLsizei written = 0;
  glGetProgramBinary(program.id(), length, &written, &format, out.data());
  out.resize(std::size_t(std::max(written, 0)));
  return out;
}

Result<Program> program_from_binary(GLenum format, const std::vector<std::uint8_t>& binary) {
  GLint formats = 0;
  glGetIntegerv(GL_NUM_PROGRAM_BINARY_FORMATS, &formats);
  std::vector<GLint> supported(std::size_t(std::max(formats, 0)));
  if (formats > 0) glGetIntegerv(GL_PROGRAM_BINARY_FORMATS, supported.data());
  if (std::find(supported.begin(), supported.end(), GLint(format)) == supported.end())
    return Error{"", "program binary", "format not supported by this driver"};
  Program program(glCreateProgram());
  glProgramBinary(program.id(), format, binary.data(), GLsizei(binary.size()));
  GLint ok = 0;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (!ok) return Error{"", "program binary", "rejected by the driver"};
  return program;
}

}  // namespace kaskad::gpu
