// Programs by (pass, variant key). Compiles on first use or ahead of time (prewarm), caches linked
// program binaries on disk (GL_ARB_get_program_binary) keyed by a hash of the driver string and
// the preprocessed sources, and reloads shader files that changed on disk (hot reload), keeping
// the last good program when a new version fails to compile.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/features/feature_manifest.h"
#include "runtime/features/variant_key.h"

namespace kaskad::render {

struct ShaderStats {
  int programs_compiled = 0;      ///< built from source (cache misses and cache-less builds)
  int cache_hits = 0;             ///< loaded from the binary cache
  double compile_ms = 0.0;        ///< preprocess + compile + link (or binary load) time, total
  int runtime_compiles = 0;       ///< programs built after the first frame (should stay 0)
  int reloads = 0;                ///< programs rebuilt by hot reload
};

class ShaderLibrary {
 public:
  /// `shader_dir` holds the GLSL files and features.json. `cache_dir` empty: no binary cache.
  /// `oracle`: build the über-shader test oracle instead of variants (tests only).
  static Result<std::unique_ptr<ShaderLibrary>> create(const std::filesystem::path& shader_dir,
                                                       const std::filesystem::path& cache_dir,
                                                       bool oracle = false);
  ~ShaderLibrary();

  /// The program for a pass and key (key filtered for the pass first). Hot path: one hash probe;
  /// must stay cheap because it runs once per program switch in every pass. A miss builds it
  /// (content errors come back as Error; the key must be valid: precondition). The library owns
  /// the program: the reference stays valid until hot reload replaces it or the library goes.
  Result<gpu::ProgramRef> program(Pass pass, VariantKey key);

  /// Builds every requested program now (scene load), so frames do not compile.
  Status prewarm(std::span<const ProgramRequest> requests);

  /// Marks the first frame as done: programs built afterwards count as runtime compiles.
  void first_frame_done() { first_frame_done_ = true; }

  /// Rebuilds programs whose source files changed since they were built. A failure keeps the
  /// last good program and is returned (log mapped to file:line); successes count in reloads.
  std::vector<Error> reload_changed();

  const FeatureManifest& manifest() const { return manifest_; }
  const ShaderStats& stats() const { return stats_; }
  std::size_t program_count() const { return programs_.size(); }
  bool binary_cache_supported() const { return binary_formats_ > 0; }
  /// Keys built so far for a pass (for tests and `kaskad variants`).
  std::vector<VariantKey> built_keys(Pass pass) const;
  /// The test oracle's über-programs select material features by a uniform (features.glsl);
  /// variants are compiled with them. Draws with such programs set it (DrawState).
  bool features_by_uniform() const { return oracle_; }

 private:
  ShaderLibrary() = default;
  struct Entry {
    gpu::Program program;
    std::vector<std::filesystem::path> files;  // every source file, for hot reload
    // min(), not {}: libstdc++'s file clock epoch is in 2174, so real times are negative.
    std::filesystem::file_time_type newest = std::filesystem::file_time_type::min();
  };
  Result<Entry> build(Pass pass, VariantKey key, bool reload);

  std::filesystem::path dir_, cache_dir_;
  bool oracle_ = false;
  FeatureManifest manifest_;
  std::string driver_;  // vendor | renderer | version: part of the cache hash
  int binary_formats_ = 0;
  bool first_frame_done_ = false;
  std::unordered_map<std::uint64_t, Entry> programs_;  // key: pass << 32 | variant bits
  ShaderStats stats_;
};


/// Default binary cache folder: $KASKAD_SHADER_CACHE ("off" disables), else
/// $XDG_CACHE_HOME/kaskad/shaders, else ~/.cache/kaskad/shaders.
std::filesystem::path default_shader_cache_dir();

}  // namespace kaskad::render
