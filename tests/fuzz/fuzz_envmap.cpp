// Fuzz entry point for environment-map loading (runtime/assets/env_map.h): layout detection,
// face-size checks, cross cutting, equirect and sphere resampling, the 3ds Max conversion, and
// the maths on whatever values the decoders produce (NaN, inf, huge). Any outcome but a crash, a
// sanitizer report or a hang is fine.
//
// Input: byte 0 picks the options (bits 0-2: the layout, EnvLayout's order modulo 6; bit 3: the
// 3ds Max conversion; bits 4-5: face_size 0, 3, 8 or 17); the rest is an image file. In the
// faces layout it is the +X face beside five valid 4 x 4 faces; otherwise it is the whole map.
//
// With libFuzzer: clang++ -fsanitize=fuzzer,address,undefined ... fuzz_envmap.cpp (+ runtime)
// Without (g++):  -DKASKAD_FUZZ_STANDALONE adds a main() that runs deterministic mutations of
//                 tiny crosses, panoramas, sphere maps and faces written by save_image.
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"

namespace {

/// Per-process scratch folder (the loaders read files), removed at exit.
const std::filesystem::path& scratch() {
  struct Dir {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("kaskad_fuzz_envmap_" + std::to_string(::getpid()));
    Dir() {
      std::filesystem::create_directories(path);
      // Five valid faces for the faces layout; the input becomes f_px.
      kaskad::Image face;
      face.width = face.height = 4;
      face.channels = 3;
      face.pixels.assign(48, 0.5f);
      for (const char* s : {"nx", "py", "ny", "pz", "nz"})
        (void)kaskad::save_image(path / (std::string("f_") + s + ".png"), face);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

void write(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t mode = data[0];
  kaskad::EnvLoadOptions options;
  options.layout = kaskad::EnvLayout(mode % 8 % 6);
  options.z_up_3dsmax = (mode & 8) != 0;
  constexpr std::array<int, 4> kFaceSizes = {0, 3, 8, 17};
  options.face_size = kFaceSizes[(mode >> 4) & 3];

  const bool faces = options.layout == kaskad::EnvLayout::faces;
  const auto file = scratch() / (faces ? "f_px.png" : "map.img");
  write(file, data + 1, size - 1);
  auto cube = kaskad::load_cube_map(faces ? scratch() / "f_*.png" : file, options);
  static const bool verbose = std::getenv("KASKAD_FUZZ_VERBOSE") != nullptr;
  if (verbose) {
    std::fprintf(stderr, "outcome (%s): %s\n", kaskad::env_layout_name(options.layout),
                 cube ? "loaded" : cube.error().to_string().c_str());
  }
  if (cube) {
    // The maths on decoded values.
    const kaskad::SphereMap sphere = kaskad::sphere_map_from_cube(*cube, 9);
    float sum = 0.0f;
    for (const glm::vec3 d : {glm::vec3(1, 2, 3), glm::vec3(0, 0, -1), glm::vec3(-1, 0, 0)})
      sum += kaskad::sample_cube(*cube, d).r + kaskad::sample_sphere(sphere, d).g;
    (void)sum;
  }
  if (options.layout == kaskad::EnvLayout::sphere) {
    auto sphere = kaskad::load_sphere_map(file);
    if (sphere) (void)kaskad::sample_sphere(*sphere, glm::vec3(0.2f, 0.1f, 0.9f));
  }
  return 0;
}

#ifdef KASKAD_FUZZ_STANDALONE
#include <vector>

#include "tests/fuzz/fuzz_mutate.h"

namespace {

/// Tiny maps for every layout, written by save_image, each behind its option byte.
std::vector<kaskad::fuzz::Bytes> generated_seeds() {
  struct Seed {
    const char* name;
    int width, height, channels;
    std::uint8_t mode;
  };
  const Seed kSeeds[] = {
      {"face.png", 4, 4, 3, 1},            // faces
      {"face.exr", 4, 4, 4, 1 | 8},        // faces, 3ds Max
      {"hcross.png", 8, 6, 3, 0},          // auto: horizontal cross
      {"hcross.exr", 8, 6, 4, 2 | 8},      // horizontal cross, 3ds Max
      {"vcross.png", 6, 8, 4, 3 | 16},     // vertical cross, face_size 3
      {"pano.hdr", 8, 4, 3, 4},            // equirect
      {"pano.exr", 16, 8, 3, 0 | 32},      // auto: equirect, face_size 8
      {"ball.png", 6, 6, 3, 5},            // sphere
      {"ball.tif", 5, 5, 1, 0 | 48},       // auto: sphere, face_size 17
  };
  const auto dir = scratch() / "seeds";
  std::filesystem::create_directories(dir);
  std::vector<kaskad::fuzz::Bytes> seeds;
  for (const Seed& s : kSeeds) {
    kaskad::Image image;
    image.width = s.width;
    image.height = s.height;
    image.channels = s.channels;
    for (int i = 0; i < s.width * s.height * s.channels; ++i)
      image.pixels.push_back(float((i * 37) % 101) / 50.0f);
    if (!kaskad::save_image(dir / s.name, image).ok()) continue;
    kaskad::fuzz::Bytes bytes = kaskad::fuzz::read_file(dir / s.name);
    bytes.insert(bytes.begin(), s.mode);
    seeds.push_back(std::move(bytes));
  }
  return seeds;
}

}  // namespace

int main(int argc, char** argv) {
  return kaskad::fuzz::run_standalone(argc, argv, generated_seeds(), &LLVMFuzzerTestOneInput);
}
#endif  // KASKAD_FUZZ_STANDALONE
