#include "runtime/app/schema_command.h"

#include <cstdio>
#include <system_error>

#include "runtime/app/playback.h"
#include "runtime/app/player.h"
#include "runtime/assets/scene_schema.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"

namespace kaskad {

int run_schema_command(const std::filesystem::path& out_dir, bool check) {
  auto manifest = render::FeatureManifest::load(content_dir() / "shaders" / "features.json");
  if (!manifest) {
    std::fprintf(stderr, "kaskad: error: %s\n", manifest.error().to_string().c_str());
    return 1;
  }
  if (!check) {
    std::error_code ec;
    // One level, the folder named (its parent was checked with the command line).
    if (!std::filesystem::exists(out_dir, ec)) std::filesystem::create_directory(out_dir, ec);
    if (ec) {
      std::fprintf(stderr, "kaskad: error: %s: cannot create the folder: %s\n",
                   out_dir.string().c_str(), ec.message().c_str());
      return 1;
    }
  }
  int stale = 0;
  auto files = reference_files(*manifest);
  files.emplace_back("playback.schema.json", playback_schema().dump(2) + "\n");
  for (const auto& [name, text] : files) {
    const std::filesystem::path path = out_dir / name;
    if (check) {
      auto committed = read_file_bytes(path, std::uintmax_t(64) << 20);
      if (!committed || std::string(committed->begin(), committed->end()) != text) {
        std::fprintf(stderr, "kaskad: %s %s the field tables: run `kaskad schema --out %s`\n",
                     path.string().c_str(), committed ? "differs from" : "is missing, made from",
                     out_dir.string().c_str());
        ++stale;
      }
      continue;
    }
    if (Status s = write_file_atomic(path, text); !s) {
      std::fprintf(stderr, "kaskad: error: %s\n", s.error().to_string().c_str());
      return 1;
    }
    std::printf("wrote %s\n", path.string().c_str());
  }
  if (check && stale == 0) std::printf("%s: up to date with the field tables\n", out_dir.string().c_str());
  return stale == 0 ? 0 : 1;
}

}  // namespace kaskad
