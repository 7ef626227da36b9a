// Fuzz target for scene files: parse + canonicalise + an override, never crash. With
// KASKAD_FUZZ_STANDALONE it runs N deterministic mutations of content/scenes/*.json.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "runtime/assets/scene_io.h"
#include "runtime/core/json_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The readers' own JSON boundary: every nlohmann exception must become a content error.
  auto doc = kaskad::json_reader::parse_json_text(text, "fuzz.json");
  if (!doc) return 0;
  auto scene = kaskad::parse_scene(*doc, "fuzz.json");
  if (!scene.ok()) return 0;
  nlohmann::json canonical = kaskad::scene_to_json(*scene);
  (void)kaskad::apply_override(canonical, "shadow.map_size=512");
  auto again = kaskad::parse_scene(canonical, "fuzz.json");
  if (!again.ok()) {
    std::fprintf(stderr, "canonical document failed to parse: %s\n", again.error().to_string().c_str());
    __builtin_trap();  // the canonical form of a valid scene must always be valid
  }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include "tests/fuzz/fuzz_mutate.h"

int main(int argc, char** argv) {
  if (kaskad::fuzz::replay_files(argc, argv, &LLVMFuzzerTestOneInput)) return 0;
  const int iterations = argc > 1 ? std::atoi(argv[1]) : 1000;
  std::vector<std::string> seeds;
  for (const auto& f : std::filesystem::directory_iterator(std::filesystem::path(KASKAD_CONTENT_DIR) / "scenes")) {
    if (f.path().extension() != ".json") continue;
    std::ifstream in(f.path(), std::ios::binary);
    seeds.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  if (seeds.empty()) {
    std::fprintf(stderr, "no seed scenes\n");
    return 1;
  }
  std::mt19937 rng(1234);
  const std::string tokens[] = {"{", "}", "[", "]", ",", ":", "\"", "0", "-1", "1e39", "null", "true",
                                "\"name\"", "\"parent\"", "\"light\"", "\"shadow\"", "1e-45", "\\u0000"};
  for (int i = 0; i < iterations; ++i) {
    std::string s = seeds[rng() % seeds.size()];
    const int edits = 1 + int(rng() % 8);
    for (int k = 0; k < edits && !s.empty(); ++k) {
      const std::size_t pos = rng() % s.size();
      switch (rng() % 4) {
        case 0: s[pos] = char(rng() % 256); break;
        case 1: s.erase(pos, 1 + rng() % 16); break;
        case 2: s.insert(pos, tokens[rng() % std::size(tokens)]); break;
        case 3: s.resize(pos); break;
      }
    }
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  }
  std::printf("fuzz_scene: %d mutated inputs, no crash\n", iterations);
  return 0;
}
#endif
