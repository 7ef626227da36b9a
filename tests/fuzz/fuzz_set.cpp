// Fuzz target for `--set KEY=VALUE` (apply_override in runtime/assets/scene_io.h): each line of
// the input is one assignment, applied in order to the canonical document of the default scene
// (as read_scene does), which is then parsed. Any outcome but a crash, a sanitizer report or a
// hang is fine; a document that parses must survive a second canonical round trip.
//
// With libFuzzer: the `fuzz` preset (scripts/fuzz.sh set).
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of a
//                 few valid assignments (see fuzz_mutate.h), or replays files and folders.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/assets/scene_io.h"

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined (a string: the path of the repository's content/)"
#endif

namespace {

/// The canonical document of content/scenes/default.json, read once.
const nlohmann::json& canonical_default() {
  static const nlohmann::json doc = [] {
    auto scene = kaskad::read_scene(std::filesystem::path(KASKAD_CONTENT_DIR) / "scenes" / "default.json");
    if (!scene) {
      std::fprintf(stderr, "%s\n", scene.error().to_string().c_str());
      std::abort();
    }
    return kaskad::scene_to_json(*scene);
  }();
  return doc;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nlohmann::json doc = canonical_default();
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0, lines = 0;
  while (start <= text.size() && lines < 64) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    if (!kaskad::apply_override(doc, text.substr(start, end - start)).ok()) return 0;
    start = end + 1;
    ++lines;
  }
  auto scene = kaskad::parse_scene(doc, "fuzz.json");
  if (!scene) return 0;
  auto again = kaskad::parse_scene(kaskad::scene_to_json(*scene), "fuzz.json");
  if (!again) {
    std::fprintf(stderr, "canonical document failed to parse: %s\n", again.error().to_string().c_str());
    __builtin_trap();
  }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include "tests/fuzz/fuzz_mutate.h"

int main(int argc, char** argv) {
  std::vector<kaskad::fuzz::Bytes> seeds;
  for (const char* s :
       {"shadow.map_size=1024", "sun.light.intensity=3\nrender.width=64",
        "box_resting.transform.translation.1=2\nshadow.filter=\"none\"", "shadow.cascade_count=8",
        "camera.camera.fov_y_deg=40\nrender.exposure=0.5\nshadow.lambda=1",
        "render.ambient=[0.1,0.2,0.3]", "sun.light={\"type\":\"spot\"}"})
    seeds.emplace_back(s, s + std::char_traits<char>::length(s));
  return kaskad::fuzz::run_standalone(argc, argv, seeds, &LLVMFuzzerTestOneInput);
}
#endif  // KASKAD_FUZZ_STANDALONE
