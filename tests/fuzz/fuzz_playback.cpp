// Fuzz target for playback files (runtime/app/playback.h): parse the bytes as a playback file,
// then sample every track it accepted at a few times (interpolation with whatever keys got
// through). Any outcome but a crash, a sanitizer report or a hang is fine.
//
// With libFuzzer: the `fuzz` preset (scripts/fuzz.sh playback).
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of
//                 tests/playback/*.json (see fuzz_mutate.h), or replays files and folders.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/app/playback.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto pb = kaskad::parse_playback(text, "fuzz/playback.json");
  static const bool verbose = std::getenv("KASKAD_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "outcome: %s\n", pb ? "parsed" : pb.error().to_string().c_str());
  if (!pb) return 0;
  std::vector<const kaskad::Track*> tracks;
  if (pb->camera) tracks.push_back(&*pb->camera);
  for (const auto& t : pb->tracks) tracks.push_back(&t);
  for (const kaskad::Track* t : tracks)
    for (double time : {-1.0, 0.0, 0.37, 1.0, 1e6}) {
      const kaskad::PoseKey k = kaskad::sample_track(*t, time);
      if (k.rotation && !std::isfinite(k.rotation->w)) {
        std::fprintf(stderr, "non-finite rotation from accepted keys\n");
        __builtin_trap();  // accepted keys must interpolate to finite poses
      }
    }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include <algorithm>
#include <filesystem>

#include "tests/fuzz/fuzz_mutate.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<kaskad::fuzz::Bytes> seeds;
  for (const auto& f : kaskad::fuzz::seed_files(
           fs::path(KASKAD_CONTENT_DIR) / ".." / "tests" / "playback", {".json"}))
    seeds.push_back(kaskad::fuzz::read_file(f));
  return kaskad::fuzz::run_standalone(argc, argv, seeds, &LLVMFuzzerTestOneInput);
}
#endif  // KASKAD_FUZZ_STANDALONE
