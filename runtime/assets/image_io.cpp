// Image files through OpenImageIO 2.4.
//
// Every read goes through memory (BoundedMemReader, a Filesystem::IOMemReader) with an explicitly chosen reader: the
// format comes from the file's magic bytes, then the MIME type, then the extension. We never let
// OIIO "try every reader in turn" on unknown bytes (what ImageInput::open(filename) does when the
// extension does not match), so corrupt or hostile data reaches at most one decoder.
#include "runtime/assets/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <string_view>
#include <system_error>

#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"

#if defined(__SANITIZE_ADDRESS__)
#define KASKAD_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KASKAD_LSAN 1
#endif
#endif
#ifdef KASKAD_LSAN
#include <sanitizer/common_interface_defs.h>
#include <sanitizer/lsan_interface.h>
#endif

namespace kaskad {
namespace {

/// OpenImageIO 2.4's PNG reader leaks a few bytes whenever libpng hits the end of truncated data:
/// its read callback builds an error string and png_error() longjmps over the destructor. Under
/// LeakSanitizer, allocations made inside OIIO's open/read calls are therefore not leak-checked
/// (scoped tightly: our own buffers are allocated outside). No-op in normal builds.
class IgnoreLeaksInOiio {
 public:
#ifdef KASKAD_LSAN
  IgnoreLeaksInOiio() {
    __lsan_disable();
  }
  ~IgnoreLeaksInOiio() {
    __lsan_enable();
  }
#else
  IgnoreLeaksInOiio() = default;
#endif
  IgnoreLeaksInOiio(const IgnoreLeaksInOiio&) = delete;
  IgnoreLeaksInOiio& operator=(const IgnoreLeaksInOiio&) = delete;
};

/// libpng (inside OIIO's PNG reader) prints "libpng error: ..." lines to stderr itself; the same
/// text reaches us through OIIO's geterror() and ends up in our error message. While a decoder
/// runs, the process's stderr therefore goes to /dev/null, so raw library lines never reach the
/// user (docs/guide/bad_input.md, "How files are read"). Sanitizer reports keep the real stderr (a duplicate of it).
/// Serialised: the file descriptor is process-wide.
class QuietStderr {
 public:
  QuietStderr() : lock_(mutex()) {
    static const int real = ::dup(2);
#ifdef KASKAD_LSAN
    static const bool reports_kept = [] {
      __sanitizer_set_report_fd(reinterpret_cast<void*>(static_cast<std::intptr_t>(real)));
      return true;
    }();
    (void)reports_kept;
#endif
    (void)real;
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, 2);
      ::close(null);
    }
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, 2);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::unique_lock<std::mutex> lock_;
  int saved_ = -1;
};

/// Largest image we decode, in float values (width * height * channels): 2^28 floats = 1 GiB,
/// e.g. 16384 x 16384 x 1 or 8192 x 8192 x 4. Guards against headers that claim absurd sizes.
constexpr std::uint64_t kMaxImageValues = std::uint64_t(1) << 28;
/// Most values (width * height * channels) one byte of image data may decode to; see decode().
constexpr std::uint64_t kMaxValuesPerByte = 65536;
/// Limits per side and on channels, checked before decoding too: OIIO reads in chunks of up to
/// 64 scanlines (or a whole tile) and allocates that chunk by the header's sizes, so a 175-byte
/// BMP claiming 16M x 5 pixels made it ask for 12.8 GB (found by tests/fuzz/fuzz_image.cpp).
constexpr int kMaxImageSide = 32768;
constexpr int kMaxChannels = 16;

/// Files larger than this are refused before reading them into memory (2 GiB).
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 31;

bool starts_with(const std::uint8_t* data, std::size_t size, std::string_view magic) {
  return size >= magic.size() && std::memcmp(data, magic.data(), magic.size()) == 0;
}

/// OIIO format name from the first bytes of the data; empty when no known signature matches.
std::string format_from_magic(const std::uint8_t* d, std::size_t n) {
  using namespace std::string_view_literals;
  if (starts_with(d, n, "\x89PNG\r\n\x1a\n"sv)) return "png";
  if (starts_with(d, n, "\xff\xd8\xff"sv)) return "jpeg";
  if (starts_with(d, n, "\x76\x2f\x31\x01"sv)) return "openexr";
  if (starts_with(d, n, "#?RADIANCE"sv) || starts_with(d, n, "#?RGBE"sv)) return "hdr";
  if (starts_with(d, n, "II*\0"sv) || starts_with(d, n, "MM\0*"sv)) return "tiff";
  if (starts_with(d, n, "GIF8"sv)) return "gif";
  if (n >= 12 && starts_with(d, n, "RIFF"sv) && std::memcmp(d + 8, "WEBP", 4) == 0) return "webp";
  if (starts_with(d, n, "8BPS"sv)) return "psd";
  if (starts_with(d, n, "DDS "sv)) return "dds";
  if (starts_with(d, n, "BM"sv)) return "bmp";
  return {};
}

/// OIIO format name for a MIME type (glTF images carry one); empty when unknown.
std::string format_from_mime(const std::string& mime) {
  if (mime == "image/png") return "png";
  if (mime == "image/jpeg") return "jpeg";
  if (mime == "image/webp") return "webp";
  if (mime == "image/bmp") return "bmp";
  if (mime == "image/gif") return "gif";
  if (mime == "image/x-exr" || mime == "image/aces") return "openexr";
  return {};
}

// The extension as a format name: lower case, without the dot ("png").
std::string extension_format(const std::filesystem::path& path) {
  const std::string ext = lowercase_extension(path);
  return ext.empty() ? ext : ext.substr(1);
}

/// The still-image formats we let OIIO decode. Debian's OIIO also has readers for camera RAW,
/// video (ffmpeg), DICOM, FITS, OpenVDB, ...: decoders a texture never needs and that would only
/// widen what a hostile file could reach.
constexpr std::string_view kAllowedFormats[] = {"png",   "jpeg", "openexr", "hdr", "tiff", "bmp",
                                                "targa", "gif",  "webp",    "pnm", "dds",  "psd"};

bool allowed_format(std::string_view format) {
  return std::find(std::begin(kAllowedFormats), std::end(kAllowedFormats), format) !=
         std::end(kAllowedFormats);
}

/// OIIO's readers of allowed formats by extension and by format name, parsed from its
/// "extension_list" attribute ("openexr:exr,sxr;tiff:tif,tiff;..."). Built once; read-only after.
const std::map<std::string, std::string>& known_formats() {
  static const std::map<std::string, std::string> formats = [] {
    std::map<std::string, std::string> m;
    std::string list;
    OIIO::getattribute("extension_list", list);
    std::size_t pos = 0;
    while (pos < list.size()) {
      std::size_t end = list.find(';', pos);
      if (end == std::string::npos) end = list.size();
      const std::string entry = list.substr(pos, end - pos);
      const std::size_t colon = entry.find(':');
      if (colon != std::string::npos && allowed_format(entry.substr(0, colon))) {
        const std::string format = entry.substr(0, colon);
        m[format] = format;
        std::size_t e = colon + 1;
        while (e < entry.size()) {
          std::size_t comma = entry.find(',', e);
          if (comma == std::string::npos) comma = entry.size();
          m.emplace(entry.substr(e, comma - e), format);
          e = comma + 1;
        }
      }
      pos = end + 1;
    }
    return m;
  }();
  return formats;
}

/// Picks the reader: magic bytes first (they cannot lie about the format the way a name can),
/// then the MIME type, then the extension of `name`. Empty when none is known to OIIO: passing an
/// unknown name to ImageInput::create() would make OIIO probe every reader on the bytes.
std::string choose_format(const std::uint8_t* data, std::size_t size, const std::string& name,
                          const std::string& mime) {
  std::string format = format_from_magic(data, size);
  if (format.empty()) format = format_from_mime(mime);
  if (format.empty()) format = extension_format(name);
  const auto& known = known_formats();
  const auto it = known.find(format);
  return it == known.end() ? std::string() : it->second;
}

/// OIIO error messages can span lines; keep them on one line for Error::to_string().
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s.empty() ? std::string("unknown OpenImageIO error") : s;
}

/// GIF: the decoder allocates and clears a canvas of the logical screen's size (bytes 6..9 of
/// the header, little-endian width and height) before it looks at any image in the file, so a
/// 14-byte file claiming a 25443 x 18761 screen took gigabytes and seconds (found by
/// scripts/fuzz.sh image, as a timeout; docs/guide/testing.md, "Fuzzing"). The screen is held to the limits of decoded images: at most
/// kMaxImageSide a side, kMaxImageValues RGBA values, and no more than the data could hold.
Status check_gif_screen(const std::uint8_t* d, std::size_t n, const std::string& name) {
  if (n < 10) return Error{name, "byte 0", "truncated GIF: no logical screen descriptor"};
  const int w = d[6] | (d[7] << 8), h = d[8] | (d[9] << 8);
  const std::uint64_t values = std::uint64_t(w) * std::uint64_t(h) * 4;
  if (w > kMaxImageSide || h > kMaxImageSide || values > kMaxImageValues ||
      values > std::uint64_t(n) * kMaxValuesPerByte)
    return Error{name, "byte 6",
                 "corrupt or too large: the GIF logical screen is " + std::to_string(w) + " x " +
                     std::to_string(h) + " pixels, more than " + std::to_string(n) +
                     " bytes of data can fill (at most " + std::to_string(kMaxImageSide) +
                     " a side)"};
  return {};
}

/// PNG: libpng allocates a chunk's declared length before reading it, so a 335-byte file whose
/// tEXt chunk claimed 1 GiB took over a gigabyte before failing (found by scripts/fuzz.sh
/// envmap, as a timeout under ASan; docs/guide/testing.md, "Fuzzing"). The chunks are walked first (8-byte
/// signature, then per chunk: length, type, data, CRC, up to IEND): each must fit in the file.
Status check_png_chunks(const std::uint8_t* d, std::size_t n, const std::string& name) {
  // The format can come from the extension alone: say so before reading garbage as chunks.
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n < 8 || std::memcmp(d, kSignature, 8) != 0)
    return Error{name, "", "not a PNG file (no PNG signature in its first 8 bytes)"};
  std::size_t at = 8;
  while (at < n) {
    if (n - at < 12)
      return Error{name, "byte " + std::to_string(at), "truncated PNG: a chunk header is cut off"};
    const std::uint32_t length = (std::uint32_t(d[at]) << 24) | (std::uint32_t(d[at + 1]) << 16) |
                                 (std::uint32_t(d[at + 2]) << 8) | std::uint32_t(d[at + 3]);
    const std::string type(reinterpret_cast<const char*>(d + at + 4), 4);
    if (std::uint64_t(length) + 12 > n - at) {
      std::string printable;
      for (char c : type) printable += std::isalpha(static_cast<unsigned char>(c)) ? c : '?';
      return Error{name, "byte " + std::to_string(at),
                   "corrupt or truncated PNG: the " + printable + " chunk claims " +
                       std::to_string(length) + " bytes, only " + std::to_string(n - at - 12) +
                       " follow"};
    }
    at += std::size_t(length) + 12;
    if (type == "IEND") break;
  }
  return {};
}

/// BMP: OIIO's reader seeks to the pixel data offset of the file header (bytes 10..13) without
/// checking it, and its in-memory reader does not check a seek before the start: a 174-byte file
/// whose offset was 0xffffffca (-54) made it read 6 bytes in front of the buffer (a heap overflow
/// found by fuzz_image under ASan). The header is checked first: the info header (size at byte 14)
/// must fit in the file and the pixel data must start after it and inside the file.
Status check_bmp_header(const std::uint8_t* d, std::size_t n, const std::string& name) {
  auto u32 = [&](std::size_t at) {
    return std::uint32_t(d[at]) | (std::uint32_t(d[at + 1]) << 8) |
           (std::uint32_t(d[at + 2]) << 16) | (std::uint32_t(d[at + 3]) << 24);
  };
  if (n < 18) return Error{name, "byte 0", "truncated BMP: no file and info headers"};
  const std::uint64_t offset = u32(10), info = u32(14);
  if (14 + info > n)
    return Error{name, "byte 14", "corrupt or truncated BMP: the info header claims " +
                                      std::to_string(info) + " bytes, the file has " +
                                      std::to_string(n)};
  if (offset < 14 + info || offset >= n)
    return Error{name, "byte 10", "corrupt BMP: the pixel data offset " + std::to_string(offset) +
                                      " is not between the end of the headers (" +
                                      std::to_string(14 + info) + ") and the end of the file (" +
                                      std::to_string(n) + ")"};
  return {};
}

/// Decodes `size` bytes with the reader for `format`. `name` is only used in messages.
/// OpenEXR allocates while reading the header, before OIIO hands us anything: a 626-byte file
/// whose string attribute claimed 2 GB made it take 2 GB (found by scripts/fuzz.sh image), and a
/// huge data window sizes its line-offset table. So the (first) header is walked here first
/// (OpenEXR file layout: magic, version, then attributes `name\0 type\0 int32 size, value` up
/// to an empty name): every attribute must fit in the file, and the data and display windows
/// must be at most kMaxImageSide a side.
Status check_exr_windows(const std::uint8_t* d, std::size_t n, const std::string& name) {
  std::size_t at = 8;
  auto text = [&](std::string& out) {
    out.clear();
    while (at < n && d[at] != 0 && out.size() < 256) out += char(d[at++]);
    if (at >= n || d[at] != 0) return false;
    ++at;
    return true;
  };
  std::string attr, type;
  while (at < n) {
    if (!text(attr)) break;  // truncated headers are the decoder's to report
    if (attr.empty()) break;
    if (!text(type) || n - at < 4) break;
    std::int32_t length = 0;
    std::memcpy(&length, d + at, 4);
    at += 4;
    if (length < 0 || std::size_t(length) > n - at)
      return Error{name, "byte " + std::to_string(at - 4),
                   "corrupt or truncated: the EXR header attribute '" + attr + "' claims " +
                       std::to_string(length) + " bytes, but only " + std::to_string(n - at) +
                       " follow"};
    if ((attr == "dataWindow" || attr == "displayWindow") && type == "box2i" && length == 16) {
      std::int32_t box[4];
      std::memcpy(box, d + at, 16);
      const std::int64_t w = std::int64_t(box[2]) - box[0] + 1, h = std::int64_t(box[3]) - box[1] + 1;
      if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
        return Error{name, "byte " + std::to_string(at),
                     "corrupt or too large: the EXR " + attr + " is " + std::to_string(w) + " x " +
                         std::to_string(h) + " pixels (at most " + std::to_string(kMaxImageSide) +
                         " a side)"};
    }
    at += std::size_t(length);
  }
  return {};
}

// OIIO 2.4's IOMemReader::pread copies past the end of its buffer when asked to read from an
// offset beyond it (the size left underflows): an EXR whose line offset table points past the
// end of the data overflowed the heap (found by fuzz_image and fuzz_envmap). Here a read stops
// at the end of the buffer, as a file read does.
class BoundedMemReader final : public OIIO::Filesystem::IOMemReader {
 public:
  using IOMemReader::IOMemReader;
  size_t pread(void* buf, size_t size, int64_t offset) override {
    const auto end = std::int64_t(m_buf.size());
    if (offset < 0 || offset >= end) return 0;
    size = std::min(size, std::size_t(end - offset));
    std::memcpy(buf, m_buf.data() + offset, size);
    return size;
  }
  size_t read(void* buf, size_t size) override {
    const size_t n = pread(buf, size, m_pos);
    m_pos += int64_t(n);
    return n;
  }
};

Result<Image> decode(const std::uint8_t* data, std::size_t size, const std::string& name,
                     const std::string& format) {
  if (size == 0) return Error{name, "", "empty image data (0 bytes)"};
  if (format.empty()) {
    return Error{name, "",
                 "not a recognised image format (no known signature, MIME type or "
                 "file extension)"};
  }

  if (format == "openexr") KASKAD_TRY(check_exr_windows(data, size, name));
  if (format == "gif") KASKAD_TRY(check_gif_screen(data, size, name));
  if (format == "png") KASKAD_TRY(check_png_chunks(data, size, name));
  if (format == "bmp") KASKAD_TRY(check_bmp_header(data, size, name));
  BoundedMemReader proxy(data, size);
  // The proxy must travel in the open() configuration: handing it to create() alone is not
  // enough for every reader (the PNG reader then opens `name` as a file). UnassociatedAlpha keeps
  // the stored values: OIIO would otherwise premultiply PNG/TGA colour by alpha on read.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
  auto in = OIIO::ImageInput::create(format, /*do_open=*/false, &config, &proxy);
  if (!in) {
    // The plugin failed to load; geterror() also clears OIIO's global error message.
    return Error{name, "", "no " + format + " reader: " + one_line(OIIO::geterror())};
  }
  if (!in->supports("ioproxy")) {
    return Error{name, "",
                 std::string("the ") + in->format_name() + " reader cannot decode from memory"};
  }

  OIIO::ImageSpec spec;
  bool opened = false;
  std::string open_error;
  {
    [[maybe_unused]] IgnoreLeaksInOiio ignore;
    opened = in->open(name, spec, config);
    if (!opened) open_error = in->geterror();
  }
  if (!opened) {
    return Error{
        name, "",
        "not a valid " + std::string(in->format_name()) + " image: " + one_line(open_error)};
  }
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth < 1) {
    return Error{name, "",
                 "zero-sized image (" + std::to_string(spec.width) + " x " +
                     std::to_string(spec.height) + ", " + std::to_string(spec.nchannels) +
                     " channels)"};
  }
  if (spec.depth > 1) return Error{name, "", "volume images are not supported"};
  if (spec.width > kMaxImageSide || spec.height > kMaxImageSide || spec.nchannels > kMaxChannels ||
      spec.tile_width > kMaxImageSide || spec.tile_height > kMaxImageSide || spec.tile_depth > 1) {
    return Error{name, "",
                 "image too large (" + std::to_string(spec.width) + " x " +
                     std::to_string(spec.height) + " pixels, " + std::to_string(spec.nchannels) +
                     " channels; at most " + std::to_string(kMaxImageSide) + " pixels a side and " +
                     std::to_string(kMaxChannels) + " channels)"};
  }
  const std::uint64_t values =
      std::uint64_t(spec.width) * std::uint64_t(spec.height) * std::uint64_t(spec.nchannels);
  if (values > kMaxImageValues) {
    return Error{name, "",
                 "image too large (" + std::to_string(spec.width) + " x " +
                     std::to_string(spec.height) + " x " + std::to_string(spec.nchannels) +
                     " values, at most 2^28)"};
  }
  // No codec we allow packs more than a few thousand values into one byte (deflate's limit is
  // about 1000:1), so a header that claims far more than the data could hold is refused before
  // the buffers are allocated: a 626-byte EXR claiming a huge data window made the decoder take
  // gigabytes and seconds before it failed (found by scripts/fuzz.sh image; docs/guide/testing.md,
  // "Fuzzing").
  if (values > std::uint64_t(size) * kMaxValuesPerByte) {
    return Error{name, "",
                 "corrupt or truncated: the header claims " + std::to_string(spec.width) + " x " +
                     std::to_string(spec.height) + " x " + std::to_string(spec.nchannels) +
                     " values, more than " + std::to_string(size) + " bytes of data can hold"};
  }

  Image image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.channel_names = spec.channelnames;
  image.pixels.resize(values);
  bool read = false;
  std::string read_error;
  {
    [[maybe_unused]] IgnoreLeaksInOiio ignore;
    read = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data());
    if (!read) read_error = in->geterror();
    in->close();
  }
  if (!read) return Error{name, "", "corrupt or truncated image data: " + one_line(read_error)};
  return image;
}

/// Formats written as 32-bit float; everything else is written as 8 bits per channel.
bool is_float_format(const std::string& ext) {
  return ext == "exr" || ext == "hdr" || ext == "tif" || ext == "tiff" || ext == "pfm";
}

/// Quantises [0,1] to 8 bits, round to nearest; NaN becomes 0 (clamp alone would keep NaN).
std::uint8_t to_unorm8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  return std::uint8_t(std::lround(v * 255.0f));
}

}  // namespace

Result<Image> load_image(const std::filesystem::path& path) {
  try {
    auto bytes = read_file_bytes(path, kMaxFileBytes);
    if (!bytes) return bytes.error();
    const auto& b = bytes.value();
    [[maybe_unused]] QuietStderr quiet;
    return decode(b.data(), b.size(), path.string(),
                  choose_format(b.data(), b.size(), path.string(), {}));
  } catch (const std::bad_alloc&) {
    return Error{path.string(), "", "out of memory while reading the image"};
  } catch (const std::exception& e) {
    return Error{path.string(), "", std::string("image read failed: ") + e.what()};
  }
}

Result<Image> load_image_from_memory(const void* data, std::size_t size, const std::string& name,
                                     const std::string& mime_type) {
  if (data == nullptr || size == 0) return Error{name, "", "empty image data (0 bytes)"};
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  try {
    [[maybe_unused]] QuietStderr quiet;
    return decode(bytes, size, name, choose_format(bytes, size, name, mime_type));
  } catch (const std::bad_alloc&) {
    return Error{name, "", "out of memory while decoding the image"};
  } catch (const std::exception& e) {
    return Error{name, "", std::string("image decode failed: ") + e.what()};
  }
}

Status check_image_output(const std::filesystem::path& path) {
  KASKAD_TRY(check_output_path(path));
  auto out = OIIO::ImageOutput::create(path.string());
  if (!out) {
    return Error{path.string(), "", "cannot write this image format: " + one_line(OIIO::geterror())};
  }
  return {};
}

Status save_image(const std::filesystem::path& path, const Image& image) {
  KASKAD_CHECK(image.width > 0 && image.height > 0 && image.channels > 0,
               "image must be non-empty, was " + std::to_string(image.width) + " x " +
                   std::to_string(image.height) + " x " + std::to_string(image.channels));
  KASKAD_CHECK(
      image.pixels.size() == std::size_t(image.width) * std::size_t(image.height) * image.channels,
      "pixels.size() must be width * height * channels, was " +
          std::to_string(image.pixels.size()));
  KASKAD_CHECK(image.channel_names.empty() || int(image.channel_names.size()) == image.channels,
               "channel_names must be empty or one per channel, was " +
                   std::to_string(image.channel_names.size()));

  KASKAD_TRY(check_output_path(path));  // a folder or a missing folder named as such
  const std::string name = path.string();
  const std::string ext = extension_format(path);
  // Declared before the writer, which may still use it while it is destroyed.
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  auto out = OIIO::ImageOutput::create(name);
  if (!out) {
    return Error{name, "", "cannot write this image format: " + one_line(OIIO::geterror())};
  }

  // Formats without alpha (JPEG, Radiance HDR, ...): drop the last channel of grey+alpha and RGBA
  // images (HDR refuses a fourth channel outright).
  int channels = image.channels;
  if (!out->supports("alpha") && (channels == 2 || channels == 4)) --channels;

  const bool as_float = is_float_format(ext);
  OIIO::ImageSpec spec(image.width, image.height, channels,
                       as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  // Our values are written as they are; without this OIIO un-premultiplies colour by alpha
  // when writing PNG (and rounding makes an 8-bit round trip inexact).
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (!image.channel_names.empty()) {
    spec.channelnames.assign(image.channel_names.begin(), image.channel_names.begin() + channels);
    const auto alpha = std::find(spec.channelnames.begin(), spec.channelnames.end(), "A");
    spec.alpha_channel =
        alpha == spec.channelnames.end() ? -1 : int(alpha - spec.channelnames.begin());
  }
  // Atomic output (runtime/core/atomic_file.h): encode into memory when the format's writer
  // can (PNG, EXR, ...), then write_file_atomic checks every byte and renames; otherwise the
  // writer writes a temporary file beside the target that is renamed only when complete.
  KASKAD_TRY(check_output_path(path));
  const bool in_memory = out->supports("ioproxy") && out->set_ioproxy(&memory);
  std::optional<TempFile> temp;
  if (!in_memory) {
    auto t = TempFile::create(path);
    if (!t) return t.error();
    temp.emplace(std::move(t.value()));
  }
  if (!out->open(in_memory ? name : temp->path().string(), spec)) {
    return Error{name, "", "cannot open for writing: " + one_line(out->geterror())};
  }

  // Repack into the written channel count and type; a float image may hold any value, 8-bit
  // formats get [0,1] clamped and quantised here so that rounding is ours, not the plugin's.
  const std::size_t pixel_count = std::size_t(image.width) * std::size_t(image.height);
  bool written = false;
  if (as_float) {
    std::vector<float> data(pixel_count * channels);
    for (std::size_t p = 0; p < pixel_count; ++p)
      for (int c = 0; c < channels; ++c)
        data[p * channels + c] = image.pixels[p * image.channels + c];
    written = out->write_image(OIIO::TypeDesc::FLOAT, data.data());
  } else {
    std::vector<std::uint8_t> data(pixel_count * channels);
    for (std::size_t p = 0; p < pixel_count; ++p)
      for (int c = 0; c < channels; ++c)
        data[p * channels + c] = to_unorm8(image.pixels[p * image.channels + c]);
    written = out->write_image(OIIO::TypeDesc::UINT8, data.data());
  }
  if (!written) return Error{name, "", "write failed: " + one_line(out->geterror())};
  if (!out->close()) return Error{name, "", "write failed: " + one_line(out->geterror())};
  out.reset();
  if (in_memory) return write_file_atomic(path, encoded.data(), encoded.size());
  return temp->commit();
}

std::vector<std::uint8_t> to_rgba8(const Image& image) {
  const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
  std::vector<std::uint8_t> out(n * 4);
  const int c = image.channels;
  for (std::size_t p = 0; p < n; ++p) {
    const float* s = &image.pixels[p * std::size_t(c)];
    out[p * 4 + 0] = to_unorm8(s[0]);
    out[p * 4 + 1] = to_unorm8(c >= 3 ? s[1] : s[0]);
    out[p * 4 + 2] = to_unorm8(c >= 3 ? s[2] : s[0]);
    out[p * 4 + 3] = to_unorm8(c == 2 ? s[1] : c >= 4 ? s[3] : 1.0f);
  }
  return out;
}

Result<ImageDiff> compare_images(const Image& a, const Image& b, float fail_threshold,
                                 float warn_threshold, float diff_scale) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    return Error{"", "image compare",
                 "sizes differ: " + std::to_string(a.width) + "x" + std::to_string(a.height) + "x" +
                     std::to_string(a.channels) + " against " + std::to_string(b.width) + "x" +
                     std::to_string(b.height) + "x" + std::to_string(b.channels)};
  const OIIO::ImageSpec spec(a.width, a.height, a.channels, OIIO::TypeDesc::FLOAT);
  // ImageBuf wraps the caller's memory: OIIO does not write through a const view.
  OIIO::ImageBuf ba(spec, const_cast<float*>(a.pixels.data()));
  OIIO::ImageBuf bb(spec, const_cast<float*>(b.pixels.data()));
  const auto r = OIIO::ImageBufAlgo::compare(ba, bb, fail_threshold, warn_threshold);
  // CompareResults::error is also set when pixels fail (OIIO 2.4): only the buffers' own
  // errors mean the comparison itself failed.
  if (ba.has_error() || bb.has_error())
    return Error{"", "image compare", "OpenImageIO: " + ba.geterror() + bb.geterror()};
  ImageDiff out;
  out.max_error = r.maxerror;
  out.mean_error = r.meanerror;
  out.failing = std::size_t(r.nfail);
  out.warning = std::size_t(r.nwarn);
  out.pixels = std::size_t(a.width) * std::size_t(a.height);
  out.diff = a;
  for (std::size_t i = 0; i < out.diff.pixels.size(); ++i)
    out.diff.pixels[i] = std::min(1.0f, std::abs(a.pixels[i] - b.pixels[i]) * diff_scale);
  if (a.channels == 4)  // an opaque picture of the colour differences
    for (std::size_t i = 3; i < out.diff.pixels.size(); i += 4) out.diff.pixels[i] = 1.0f;
  return out;
}

}  // namespace kaskad
