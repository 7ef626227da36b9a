// Fuzz target for material files (runtime/assets/material_file.h): the bytes become a material
// JSON file beside copies of the shipped textures and are loaded against the shipped feature
// manifest. Any outcome but a crash, a sanitizer report or a hang is fine.
//
// With libFuzzer: the `fuzz` preset (scripts/fuzz.sh material).
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of
//                 content/materials/*.json (see fuzz_mutate.h), or replays files and folders.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/assets/material_file.h"

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined (a string: the path of the repository's content/)"
#endif

namespace {

namespace fs = std::filesystem;

/// Per-process folder holding the input file and textures/ (the shipped ones), removed at exit.
const fs::path& work_dir() {
  struct Dir {
    fs::path path = fs::temp_directory_path() / ("kaskad_fuzz_material_" + std::to_string(::getpid()));
    Dir() {
      fs::create_directories(path);
      fs::copy(fs::path(KASKAD_CONTENT_DIR) / "materials" / "textures", path / "textures",
               fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

const kaskad::render::FeatureManifest& manifest() {
  static const kaskad::render::FeatureManifest m = [] {
    auto loaded = kaskad::render::FeatureManifest::load(fs::path(KASKAD_CONTENT_DIR) / "shaders" /
                                                        "features.json");
    if (!loaded) {
      std::fprintf(stderr, "%s\n", loaded.error().to_string().c_str());
      std::abort();
    }
    return std::move(loaded.value());
  }();
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path file = work_dir() / "input.json";
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  kaskad::AssetStore assets;
  auto material = kaskad::load_material_file(file, manifest(), assets);
  static const bool verbose = std::getenv("KASKAD_FUZZ_VERBOSE") != nullptr;
  if (verbose)
    std::fprintf(stderr, "outcome: %s\n", material ? "loaded" : material.error().to_string().c_str());
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include <algorithm>

#include "tests/fuzz/fuzz_mutate.h"

int main(int argc, char** argv) {
  std::vector<kaskad::fuzz::Bytes> seeds;
  for (const auto& f : kaskad::fuzz::seed_files(fs::path(KASKAD_CONTENT_DIR) / "materials", {".json"}))
    seeds.push_back(kaskad::fuzz::read_file(f));
  return kaskad::fuzz::run_standalone(argc, argv, seeds, &LLVMFuzzerTestOneInput);
}
#endif  // KASKAD_FUZZ_STANDALONE
