#include "editor/file_dialog.h"

#include <algorithm>
#include <system_error>

#include "runtime/core/file_io.h"

namespace fs = std::filesystem;

namespace kaskad::editor {

namespace {

// The length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlongs, no surrogates,
// at most U+10FFFF), or 0.
std::size_t utf8_length(const std::string& s, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n > s.size()) return 0;
  if (b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  return n;
}

}  // namespace

std::string display_name(const std::string& name) {
  std::string out;
  for (std::size_t i = 0; i < name.size();) {
    const std::size_t n = utf8_length(name, i);
    if (n > 0 && static_cast<unsigned char>(name[i]) >= 0x20) {
      out.append(name, i, n);
      i += n;
    } else {
      static const char* hex = "0123456789ABCDEF";
      const auto u = static_cast<unsigned char>(name[i]);
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
      ++i;
    }
  }
  return out;
}

FolderListing list_folder(const fs::path& folder, const std::vector<std::string>& extensions) {
  FolderListing listing;
  std::error_code ec;
  fs::directory_iterator it(folder, ec);
  if (ec) {
    listing.error = "cannot read " + display_name(folder.string()) + ": " + ec.message();
    return listing;
  }
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    const fs::path& p = it->path();
    const std::string name = p.filename().string();
    if (name.empty() || name[0] == '.') continue;
    std::error_code type_ec;
    const fs::file_status st = it->status(type_ec);  // follows links: a broken one fails here
    if (type_ec) continue;
    FolderEntry entry{p, display_name(name), fs::is_directory(st)};
    if (!entry.folder) {
      if (!fs::is_regular_file(st)) continue;
      if (std::find(extensions.begin(), extensions.end(), lowercase_extension(p)) == extensions.end())
        continue;
    }
    listing.entries.push_back(std::move(entry));
  }
  if (ec)
    listing.error = "cannot read all of " + display_name(folder.string()) + ": " + ec.message();
  std::sort(listing.entries.begin(), listing.entries.end(),
            [](const FolderEntry& a, const FolderEntry& b) {
              if (a.folder != b.folder) return a.folder;
              return a.path.filename() < b.path.filename();
            });
  return listing;
}

fs::path resolve_typed(const fs::path& folder, const std::string& typed) {
  if (typed.empty()) return {};
  const fs::path p = typed;
  return p.is_absolute() ? p : folder / p;
}

void FileDialog::enter(const fs::path& dir) {
  std::error_code ec;
  const fs::path abs = fs::absolute(dir, ec);
  folder = (ec ? dir : abs).lexically_normal();
  // "a/b/.." normalises to "a/": shown, and gone up from, as "a".
  if (!folder.has_filename() && folder != folder.root_path()) folder = folder.parent_path();
  listing = list_folder(folder, extensions());
  picked.clear();
  error.clear();
}

}  // namespace kaskad::editor
