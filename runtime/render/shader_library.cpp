#include "runtime/render/shader_library.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "runtime/core/atomic_file.h"
#include "runtime/core/hash.h"
#include "runtime/core/log.h"
#include "runtime/gpu/shader.h"

namespace kaskad::render {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr char kMagic[4] = {'K', 'S', 'K', 'B'};
constexpr std::uint32_t kCacheVersion = 1;

/// A pass's stages: vertex and fragment, or one compute shader.
struct PassFiles {
  const char* vertex;
  const char* fragment;
  const char* compute = nullptr;
};
PassFiles files_for(Pass pass) {
  switch (pass) {
    case Pass::deform: return {nullptr, nullptr, "deform.comp"};
    case Pass::depth: return {"shadow_depth.vert", "shadow_depth.frag"};
    case Pass::shadow_points: return {"shadow_points.vert", "shadow_points.frag"};
    case Pass::lom_occlusion: return {"fullscreen.vert", "lom_occlusion.frag"};
    case Pass::vsm_moments: return {"fullscreen.vert", "vsm_moments.frag"};
    case Pass::forward: break;
  }
  return {"forward.vert", "forward.frag"};
}

// The program map's key: the pass above the variant key's bits (keys use bits 0-47).
constexpr int kPassShift = 56;
constexpr std::uint64_t kKeyBits = (std::uint64_t(1) << kPassShift) - 1u;
std::uint64_t map_key(Pass pass, VariantKey key) {
  return (std::uint64_t(pass) << kPassShift) | key.bits();
}

std::string hex(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

bool read_cache(const fs::path& file, std::uint64_t hash, GLenum& format,
                std::vector<std::uint8_t>& binary) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  char magic[4];
  std::uint32_t version = 0, fmt = 0;
  std::uint64_t stored = 0, size = 0;
  in.read(magic, 4);
  in.read(reinterpret_cast<char*>(&version), 4);
  in.read(reinterpret_cast<char*>(&fmt), 4);
  in.read(reinterpret_cast<char*>(&stored), 8);
  in.read(reinterpret_cast<char*>(&size), 8);
  if (!in || std::memcmp(magic, kMagic, 4) != 0 || version != kCacheVersion || stored != hash ||
      size > (std::uint64_t(1) << 30))
    return false;
  binary.resize(std::size_t(size));
  in.read(reinterpret_cast<char*>(binary.data()), std::streamsize(size));
  format = fmt;
  return bool(in);
}

void write_cache(const fs::path& file, std::uint64_t hash, GLenum format,
                 const std::vector<std::uint8_t>& binary) {
  // The cache folder is Kaskad's own (docs/design/permutations.md, "The variant key"), so it is
  // created here.
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  const std::uint32_t fmt = format;
  const std::uint64_t size = binary.size();
  std::vector<std::uint8_t> bytes;
  auto put = [&](const void* p, std::size_t n) {
    bytes.insert(bytes.end(), static_cast<const std::uint8_t*>(p), static_cast<const std::uint8_t*>(p) + n);
  };
  put(kMagic, 4);
  put(&kCacheVersion, 4);
  put(&fmt, 4);
  put(&hash, 8);
  put(&size, 8);
  put(binary.data(), binary.size());
  // A cache that cannot be written is not an error, just slower next time; a failed write
  // leaves no partial entry behind (atomic_file.h).
  if (auto st = write_file_atomic(file, bytes); !st)
    log::debug("shader cache not written: %s", st.error().to_string().c_str());
}

}  // namespace

fs::path default_shader_cache_dir() {
  if (const char* env = std::getenv("KASKAD_SHADER_CACHE"); env && *env)
    return std::string(env) == "off" ? fs::path() : fs::path(env);
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return fs::path(xdg) / "kaskad" / "shaders";
  if (const char* home = std::getenv("HOME"); home && *home)
    return fs::path(home) / ".cache" / "kaskad" / "shaders";
  return {};
}

Result<std::unique_ptr<ShaderLibrary>> ShaderLibrary::create(const fs::path& shader_dir,
                                                             const fs::path& cache_dir,
                                                             bool oracle) {
  std::unique_ptr<ShaderLibrary> lib(new ShaderLibrary());
  lib->dir_ = shader_dir;
  lib->cache_dir_ = cache_dir;
  lib->oracle_ = oracle;
  auto manifest = FeatureManifest::load(shader_dir / "features.json");
  if (!manifest) return manifest.error();
  lib->manifest_ = std::move(manifest.value());
  auto str = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
  };
  lib->driver_ = str(GL_VENDOR) + "|" + str(GL_RENDERER) + "|" + str(GL_VERSION);
  glGetIntegerv(GL_NUM_PROGRAM_BINARY_FORMATS, &lib->binary_formats_);
  if (lib->binary_formats_ == 0 && !cache_dir.empty())
    log::info("the driver offers no program binary formats: shader binary cache off");
  return lib;
}

ShaderLibrary::~ShaderLibrary() = default;

Result<ShaderLibrary::Entry> ShaderLibrary::build(Pass pass, VariantKey key, bool reload) {
  const auto t0 = Clock::now();
  const PassFiles pf = files_for(pass);
  // The oracle compiles every material feature in and selects them by uniform (features.glsl).
  const VariantKey effective =
      oracle_ ? VariantKey(key.frame().bits() | VariantKey::kMaterialMask) : key;
  auto defines_for = [&](ShaderStage stage) {
    auto d = manifest_.defines(effective, stage);  // oracle: every material define is 1
    if (oracle_) d.emplace_back("KASKAD_UBER_ORACLE", "1");
    return d;
  };
  std::vector<gpu::ShaderSource> stages;
  for (const auto& [file, stage] : {std::pair{pf.vertex, ShaderStage::vertex},
                                    std::pair{pf.fragment, ShaderStage::fragment},
                                    std::pair{pf.compute, ShaderStage::compute}}) {
    if (file == nullptr) continue;
    auto src = gpu::preprocess_shader(dir_, file, defines_for(stage));
    if (!src) return src.error();
    stages.push_back(std::move(src.value()));
  }

  Entry entry;
  for (const gpu::ShaderSource& src : stages)
    for (const auto& f : src.files) {
      entry.files.push_back(dir_ / f);
      std::error_code ec;
      entry.newest = std::max(entry.newest, fs::last_write_time(dir_ / f, ec));
    }

  // Cache key: driver + both preprocessed sources. Editing any included file changes the text,
  // so stale binaries are never used (they are simply not found).
  std::uint64_t hash = hash_bytes(driver_);
  for (const gpu::ShaderSource& src : stages) hash = hash_bytes(src.text, hash);
  const bool use_cache = !cache_dir_.empty() && binary_formats_ > 0;
  const fs::path cache_file = cache_dir_ / (hex(hash) + ".bin");
  if (use_cache) {
    GLenum format = 0;
    std::vector<std::uint8_t> binary;
    if (read_cache(cache_file, hash, format, binary)) {
      auto p = gpu::program_from_binary(format, binary);
      if (p) {
        entry.program = std::move(p.value());
        ++stats_.cache_hits;
        stats_.compile_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        return entry;
      }
      log::debug("shader cache %s: %s; rebuilding", cache_file.string().c_str(),
                 p.error().message.c_str());
    }
  }
  auto program = stages.size() == 1 ? gpu::build_compute_program(stages[0], use_cache)
                                    : gpu::build_program(stages[0], stages[1], use_cache);
  if (!program) return program.error();
  entry.program = std::move(program.value());
  ++stats_.programs_compiled;
  if (first_frame_done_ && !reload) ++stats_.runtime_compiles;
  if (use_cache) {
    GLenum format = 0;
    const auto binary = gpu::program_binary(entry.program, format);
    if (!binary.empty()) write_cache(cache_file, hash, format, binary);
  }
  stats_.compile_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return entry;
}

Result<gpu::ProgramRef> ShaderLibrary::program(Pass pass, VariantKey key) {
  key = key.filtered_for(pass);
  if (oracle_) key = key.frame();  // one über-program per frame configuration
  // Hot path: one hash probe; a miss builds the program (and is counted).
  const std::uint64_t k = map_key(pass, key);
  if (auto it = programs_.find(k); it != programs_.end()) return gpu::ProgramRef(it->second.program);
  if (!oracle_) {
    const std::string bad = manifest_.check(key);
    KASKAD_CHECK(bad.empty(), "invalid variant key " + manifest_.describe(key) + ": " + bad);
  }
  auto entry = build(pass, key, false);
  if (!entry) return entry.error();
  const auto it = programs_.emplace(k, std::move(entry.value())).first;
  return gpu::ProgramRef(it->second.program);
}

Status ShaderLibrary::prewarm(std::span<const ProgramRequest> requests) {
  for (const ProgramRequest& r : requests) {
    auto p = program(r.pass, r.key);
    if (!p) return p.error();
  }
  return {};
}

std::vector<Error> ShaderLibrary::reload_changed() {
  std::vector<Error> errors;
  for (auto& [k, entry] : programs_) {
    fs::file_time_type newest = fs::file_time_type::min();
    for (const auto& f : entry.files) {
      std::error_code ec;
      newest = std::max(newest, fs::last_write_time(f, ec));
    }
    if (newest <= entry.newest) continue;
    const Pass pass = Pass(k >> kPassShift);
    auto rebuilt = build(pass, VariantKey(k & kKeyBits), true);
    if (!rebuilt) {
      entry.newest = newest;  // report once per change, keep the last good program
      errors.push_back(rebuilt.error());
      continue;
    }
    entry = std::move(rebuilt.value());
    ++stats_.reloads;
  }
  return errors;
}

std::vector<VariantKey> ShaderLibrary::built_keys(Pass pass) const {
  std::vector<VariantKey> keys;
  for (const auto& [k, e] : programs_)
    if (Pass(k >> kPassShift) == pass) keys.push_back(VariantKey(k & kKeyBits));
  std::sort(keys.begin(), keys.end());
  return keys;
}

}  // namespace kaskad::render
