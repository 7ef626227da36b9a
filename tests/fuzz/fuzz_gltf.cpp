// Fuzz entry point for the glTF importer: the bytes become a .glb (or, when they are JSON, a
// .gltf: the loader goes by content, not by extension) in a private temp directory and are
// imported into a fresh world. Any outcome but a crash, a sanitizer report or a hang is fine.
//
// With libFuzzer: clang++ -fsanitize=fuzzer,address,undefined ... fuzz_gltf.cpp <runtime sources>
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of the
//                 .glb/.gltf files under content/models (see fuzz_mutate.h).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/assets/gltf_loader.h"

namespace {

/// Per-process directory for the input file (and, standalone, the seeds' .bin and image files,
/// so mutated .gltf seeds still find their buffers). Removed at exit.
const std::filesystem::path& work_dir() {
  struct Dir {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("kaskad_fuzz_gltf_" + std::to_string(::getpid()));
    Dir() { std::filesystem::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = work_dir() / "input.glb";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  kaskad::ecs::World world;
  kaskad::AssetStore assets;
  const kaskad::ecs::Entity root = world.create();
  auto report = kaskad::import_gltf(path, world, assets, root, root, true);
  // KASKAD_FUZZ_VERBOSE=1 prints each outcome: shows how deep the inputs get.
  static const bool verbose = std::getenv("KASKAD_FUZZ_VERBOSE") != nullptr;
  if (verbose) {
    std::fprintf(stderr, "outcome: %s\n", report ? "imported" : report.error().to_string().c_str());
  }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include <algorithm>
#include <nlohmann/json.hpp>

#include "tests/fuzz/fuzz_mutate.h"

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined (a string: the path of the repository's content/)"
#endif

namespace {

/// A small glTF with what the content models lack: lights, all camera kinds, a sparse
/// normalized accessor, TRS and matrix nodes and a data-URI buffer.
const char* kSyntheticSeed = R"({"asset":{"version":"2.0"},"scene":0,
"extensionsUsed":["KHR_lights_punctual","KHR_mesh_quantization"],
"extensions":{"KHR_lights_punctual":{"lights":[{"type":"directional","color":[1,0.9,0.8],
"intensity":3},{"type":"spot","range":20,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.6}},
{"type":"point","intensity":100,"range":5}]}},
"scenes":[{"nodes":[0,2,3,4,5]}],
"nodes":[{"translation":[1,2,3],"rotation":[0,0.7071,0,0.7071],"scale":[2,2,2],"children":[1]},
{"mesh":0,"matrix":[0,2,0,0,-3,0,0,0,0,0,-1,0,4,5,6,1]},
{"extensions":{"KHR_lights_punctual":{"light":0}}},
{"extensions":{"KHR_lights_punctual":{"light":1}},"camera":0},
{"extensions":{"KHR_lights_punctual":{"light":2}},"camera":1},{"camera":2}],
"cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.05,"zfar":500,"aspectRatio":1.5}},
{"type":"perspective","perspective":{"yfov":1.0,"znear":0.1}},
{"type":"orthographic","orthographic":{"xmag":10,"ymag":5,"znear":0,"zfar":100}}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0},
{"attributes":{"POSITION":2},"mode":5}]}],
"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[1,0.5,0.5,1],"metallicFactor":0.2},
"emissiveFactor":[0.1,0,0],"doubleSided":true}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"},
{"componentType":5122,"normalized":true,"count":4,"type":"VEC3","sparse":{"count":1,
"indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}}}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
"buffers":[{"byteLength":44,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}]})";

void put_u32(kaskad::fuzz::Bytes& b, std::size_t at, std::uint32_t v) {
  std::memcpy(b.data() + at, &v, 4);
}

/// The .glb form of a .gltf whose first buffer is an external file: that buffer becomes the BIN
/// chunk, so mutations reach its data (Draco streams, accessors) too. Empty if not applicable.
kaskad::fuzz::Bytes embed_as_glb(const std::filesystem::path& gltf) {
  nlohmann::json doc = nlohmann::json::parse(kaskad::fuzz::read_file(gltf), nullptr, false);
  if (doc.is_discarded() || !doc.contains("buffers") || doc["buffers"].empty() ||
      !doc["buffers"][0].contains("uri")) {
    return {};
  }
  kaskad::fuzz::Bytes bin =
      kaskad::fuzz::read_file(gltf.parent_path() / doc["buffers"][0]["uri"].get<std::string>());
  doc["buffers"][0].erase("uri");
  std::string json = doc.dump();
  while (json.size() % 4 != 0) json += ' ';
  while (bin.size() % 4 != 0) bin.push_back(0);
  kaskad::fuzz::Bytes glb(20);
  glb.reserve(28 + json.size() + bin.size());  // one allocation (and no GCC 12 -Warray-bounds)
  std::memcpy(glb.data(), "glTF", 4);
  put_u32(glb, 4, 2);
  put_u32(glb, 8, std::uint32_t(28 + json.size() + bin.size()));
  put_u32(glb, 12, std::uint32_t(json.size()));
  std::memcpy(glb.data() + 16, "JSON", 4);
  glb.insert(glb.end(), json.begin(), json.end());
  glb.resize(glb.size() + 8);
  put_u32(glb, glb.size() - 8, std::uint32_t(bin.size()));
  std::memcpy(glb.data() + glb.size() - 4, "BIN", 4);
  glb.insert(glb.end(), bin.begin(), bin.end());
  return glb;
}

/// Rewrites a .glb's total length and BIN chunk length to match its size (when its JSON chunk
/// still fits), so that edits inside the chunks get past the container checks.
void fix_glb_lengths(kaskad::fuzz::Bytes& b) {
  if (b.size() < 28 || std::memcmp(b.data(), "glTF", 4) != 0) return;
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, b.data() + 12, 4);
  put_u32(b, 8, std::uint32_t(b.size()));
  const std::uint64_t bin_header = 20 + std::uint64_t(json_length);
  if (bin_header + 8 > b.size()) return;
  std::uint32_t bin_length = std::uint32_t(b.size() - bin_header - 8) & ~3u;
  put_u32(b, std::size_t(bin_header), bin_length);
  b.resize(std::size_t(bin_header) + 8 + bin_length);
  put_u32(b, 8, std::uint32_t(b.size()));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<kaskad::fuzz::Bytes> seeds;
  seeds.emplace_back(kSyntheticSeed, kSyntheticSeed + std::strlen(kSyntheticSeed));
  const auto models = std::filesystem::path(KASKAD_CONTENT_DIR) / "models";
  for (const auto& file : kaskad::fuzz::seed_files(models, {".glb", ".gltf", ".bin", ".png", ".jpg"})) {
    const auto ext = file.extension();
    if (ext == ".glb" || ext == ".gltf") {
      seeds.push_back(kaskad::fuzz::read_file(file));
      if (ext == ".gltf") {
        if (auto glb = embed_as_glb(file); !glb.empty()) seeds.push_back(std::move(glb));
      }
    } else if (ext == ".bin" || ext == ".png" || ext == ".jpg") {
      // .gltf seeds refer to these by relative URI: put them beside the input file.
      std::filesystem::copy_file(file, work_dir() / file.filename(),
                                 std::filesystem::copy_options::overwrite_existing);
    }
  }
  return kaskad::fuzz::run_standalone(argc, argv, seeds, &LLVMFuzzerTestOneInput, &fix_glb_lengths);
}
#endif  // KASKAD_FUZZ_STANDALONE
