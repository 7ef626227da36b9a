// A deterministic stand-in for libFuzzer, so the fuzz entry points also run as a smoke test
// under plain g++ with -fsanitize=address,undefined (no clang needed):
//
//   fuzz_gltf ITERATIONS [FIRST]
//   fuzz_gltf FILE...
//
// runs iterations FIRST .. FIRST+ITERATIONS-1. Iteration i mutates a seed with a generator seeded
// from i alone, so any iteration can be replayed on its own ("fuzz_gltf 1 4711"); set
// KASKAD_FUZZ_SAVE=path to also write each input there before it runs (the input of a crash is
// then left in that file); the second form replays saved inputs. Only compiled with
// KASKAD_FUZZ_STANDALONE.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace kaskad::fuzz {

using Bytes = std::vector<std::uint8_t>;
using EntryPoint = int (*)(const std::uint8_t*, std::size_t);

/// splitmix64: tiny, good enough, and identical on every platform (std distributions are not).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, n); n > 0.
  std::size_t below(std::size_t n) { return std::size_t(next() % n); }

 private:
  std::uint64_t state_;
};

/// The regular files below `dir` (recursively) with one of `extensions` (".json"), sorted:
/// directory order varies, iterations must not.
inline std::vector<std::filesystem::path> seed_files(
    const std::filesystem::path& dir, std::initializer_list<std::string_view> extensions) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
    if (entry.is_regular_file() &&
        std::find(extensions.begin(), extensions.end(), entry.path().extension().string()) !=
            extensions.end())
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

inline Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A position in `data` (size > 0): half the time among the first 256 bytes, where headers,
/// GLB chunk descriptors and the start of JSON live.
inline std::size_t position(Rng& rng, const Bytes& data) {
  const std::size_t n = data.size();
  return rng.below(2) == 0 ? rng.below(std::min<std::size_t>(n, 256)) : rng.below(n);
}

/// One random edit: bit flips, byte values, truncation, deletion, duplication, splicing with
/// another seed, random insertions, and number edits (which keep JSON parseable more often).
inline void mutate_once(Bytes& data, const std::vector<Bytes>& seeds, Rng& rng) {
  static const std::uint32_t kInteresting[] = {0u,          1u,          0x7fu,    0x80u,
                                               0xffu,       0x7fffu,     0xffffu,  0x7fffffffu,
                                               0x80000000u, 0xffffffffu, 0x10000u, 0x100u};
  static const char* kNumbers[] = {
      "-1",  "0",   "4294967295", "2147483648",          "1e39", "65536", "3",
      "255", "0.5", "-0",         "99999999999999999999"};
  if (data.empty()) {
    data.push_back(std::uint8_t(rng.next()));
    return;
  }
  // JSON text dies at almost any byte edit; give number edits (which keep it valid) half the odds.
  const bool json_text = data[0] == '{';
  switch (json_text && rng.below(2) == 0 ? 8 : rng.below(9)) {
    case 0:  // flip a bit
      data[position(rng, data)] ^= std::uint8_t(1u << rng.below(8));
      break;
    case 1:  // random byte
      data[position(rng, data)] = std::uint8_t(rng.next());
      break;
    case 2: {  // interesting little-endian value
      const std::uint32_t v = kInteresting[rng.below(std::size(kInteresting))];
      const std::size_t at = position(rng, data);
      const std::size_t width = std::size_t(1) << rng.below(3);  // 1, 2 or 4 bytes
      for (std::size_t i = 0; i < width && at + i < data.size(); ++i)
        data[at + i] = std::uint8_t(v >> (8 * i));
      break;
    }
    case 3:  // truncate
      data.resize(rng.below(data.size()));
      break;
    case 4: {  // delete a range
      const std::size_t at = rng.below(data.size());
      const std::size_t len = std::min(data.size() - at, 1 + rng.below(64));
      data.erase(data.begin() + std::ptrdiff_t(at), data.begin() + std::ptrdiff_t(at + len));
      break;
    }
    case 5: {  // duplicate a range somewhere else
      const std::size_t from = rng.below(data.size());
      const std::size_t len = std::min(data.size() - from, 1 + rng.below(64));
      const Bytes chunk(data.begin() + std::ptrdiff_t(from),
                        data.begin() + std::ptrdiff_t(from + len));
      data.insert(data.begin() + std::ptrdiff_t(rng.below(data.size() + 1)), chunk.begin(),
                  chunk.end());
      break;
    }
    case 6: {  // splice: keep a head of this input, append a tail of a (maybe other) seed
      const Bytes& other = seeds[rng.below(seeds.size())];
      if (other.empty()) break;
      data.resize(rng.below(data.size() + 1));
      const std::size_t from = rng.below(other.size());
      data.insert(data.end(), other.begin() + std::ptrdiff_t(from), other.end());
      break;
    }
    case 7: {  // insert random bytes
      const std::size_t at = rng.below(data.size() + 1);
      const std::size_t len = 1 + rng.below(16);
      for (std::size_t i = 0; i < len; ++i)
        data.insert(data.begin() + std::ptrdiff_t(at), std::uint8_t(rng.next()));
      break;
    }
    default: {  // replace the number at or after a random position (for JSON)
      std::size_t at = position(rng, data);
      while (at < data.size() && !(data[at] >= '0' && data[at] <= '9')) ++at;
      if (at == data.size()) break;
      std::size_t end = at;
      while (end < data.size() && ((data[end] >= '0' && data[end] <= '9') || data[end] == '.'))
        ++end;
      const std::string number = kNumbers[rng.below(std::size(kNumbers))];
      data.erase(data.begin() + std::ptrdiff_t(at), data.begin() + std::ptrdiff_t(end));
      data.insert(data.begin() + std::ptrdiff_t(at), number.begin(), number.end());
      break;
    }
  }
}

/// Optional repair after the edits, e.g. rewriting container lengths so that the edits reach
/// the decoders behind the container checks. Called on half of the inputs.
using Fixup = void (*)(Bytes&);

/// Iteration i's input: a seed chosen by i with 1 to 4 edits (every 16th input is unmodified).
inline Bytes make_input(const std::vector<Bytes>& seeds, std::uint64_t iteration,
                        Fixup fixup = nullptr) {
  Rng rng(0x6b61736b6164ull ^ (iteration * 0x9e3779b97f4a7c15ull));
  Bytes data = seeds[rng.below(seeds.size())];
  if (iteration % 16 == 0) return data;
  const std::size_t edits = 1 + rng.below(4);
  for (std::size_t e = 0; e < edits; ++e) mutate_once(data, seeds, rng);
  if (fixup != nullptr && rng.below(2) == 0) fixup(data);
  return data;
}

/// When argv[1] names a file or a folder (a corpus, tests/fuzz/corpus/<target>/), runs every file
/// argument and every file in the folders once, in name order (replaying saved inputs, or the
/// CTest corpus run), and returns true.
inline bool replay_files(int argc, char** argv, EntryPoint entry) {
  if (argc < 2 || !std::filesystem::exists(argv[1])) return false;
  std::size_t runs = 0;
  for (int a = 1; a < argc; ++a) {
    std::vector<std::filesystem::path> files;
    if (std::filesystem::is_directory(argv[a])) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(argv[a]))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
    } else {
      files.emplace_back(argv[a]);
    }
    for (const auto& file : files) {
      const Bytes input = read_file(file);
      entry(input.data(), input.size());
      ++runs;
    }
  }
  std::printf("%zu inputs ran clean\n", runs);
  return true;
}

/// The standalone main(): argv[1] iterations (default 1000), argv[2] first iteration (default 0).
/// When argv[1] names a file or folder, replay_files() runs those instead.
inline int run_standalone(int argc, char** argv, const std::vector<Bytes>& seeds, EntryPoint entry,
                          Fixup fixup = nullptr) {
  if (replay_files(argc, argv, entry)) return 0;
  if (seeds.empty()) {
    std::fprintf(stderr, "no seed files found\n");
    return 2;
  }
  const std::uint64_t count = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000;
  const std::uint64_t first = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 0;
  const char* save = std::getenv("KASKAD_FUZZ_SAVE");
  for (std::uint64_t i = first; i < first + count; ++i) {
    const Bytes input = make_input(seeds, i, fixup);
    if (save != nullptr) {
      std::ofstream out(save, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(input.data()), std::streamsize(input.size()));
    }
    entry(input.data(), input.size());
    if ((i + 1 - first) % 500 == 0) {
      std::fprintf(stderr, "%llu iterations done\n",
                   static_cast<unsigned long long>(i + 1 - first));
    }
  }
  std::printf("%llu iterations (%llu..%llu) ran clean over %zu seeds\n",
              static_cast<unsigned long long>(count), static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), seeds.size());
  return 0;
}

}  // namespace kaskad::fuzz
