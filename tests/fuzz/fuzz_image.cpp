// Fuzz entry point for image decoding from memory (what glTF textures go through). Any outcome
// but a crash, a sanitizer report or a hang is fine.
//
// With libFuzzer: clang++ -fsanitize=fuzzer,address,undefined ... fuzz_image.cpp image_io.cpp
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of
//                 small images: the JPEG faces and the HDR under content/env, and tiny PNG, EXR
//                 (named channels), JPEG, HDR, TIFF and BMP files written by save_image.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/assets/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto image = kaskad::load_image_from_memory(data, size, "fuzz input");
  // KASKAD_FUZZ_VERBOSE=1 prints each outcome: shows how deep the inputs get.
  static const bool verbose = std::getenv("KASKAD_FUZZ_VERBOSE") != nullptr;
  if (verbose) {
    std::fprintf(stderr, "outcome: %s\n", image ? "decoded" : image.error().to_string().c_str());
  }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include <algorithm>
#include <filesystem>

#include "tests/fuzz/fuzz_mutate.h"

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined (a string: the path of the repository's content/)"
#endif

namespace {

/// Tiny images in several formats, written by save_image and read back as bytes.
std::vector<kaskad::fuzz::Bytes> generated_seeds() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("kaskad_fuzz_image_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::vector<kaskad::fuzz::Bytes> seeds;
  for (const char* name :
       {"rgba.png", "grey.png", "rgb.jpg", "p.exr", "rgba.exr", "rgb.hdr", "rgb.tif", "rgb.bmp"}) {
    const std::string file = name;
    kaskad::Image image;
    image.width = 7;
    image.height = 5;
    image.channels = file == "grey.png" ? 1 : (file.find("rgba") == 0 ? 4 : 3);
    if (file == "p.exr") image.channel_names = {"P.X", "P.Y", "P.Z"};
    for (int i = 0; i < image.width * image.height * image.channels; ++i)
      image.pixels.push_back(float((i * 37) % 101) / 50.0f);
    if (kaskad::save_image(dir / name, image).ok())
      seeds.push_back(kaskad::fuzz::read_file(dir / name));
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return seeds;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<kaskad::fuzz::Bytes> seeds = generated_seeds();
  const auto env = std::filesystem::path(KASKAD_CONTENT_DIR) / "env";
  for (const auto& file : kaskad::fuzz::seed_files(env, {".jpg", ".hdr", ".png"}))
    seeds.push_back(kaskad::fuzz::read_file(file));
  return kaskad::fuzz::run_standalone(argc, argv, seeds, &LLVMFuzzerTestOneInput);
}
#endif  // KASKAD_FUZZ_STANDALONE
