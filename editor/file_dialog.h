// The file dialog's folder logic (`kaskad edit`: Open, Save as, Import model): listing a folder and
// resolving a typed name. Pure (no window, no ImGui); the dialog itself is drawn in editor.cpp.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kaskad::editor {

/// One row of a folder listing.
struct FolderEntry {
  std::filesystem::path path;  ///< the entry as the file system names it (any bytes)
  std::string label;           ///< its name as valid UTF-8 for display: other bytes as \xNN
  bool folder = false;         ///< a folder (or a link to one); else a regular file
};

struct FolderListing {
  std::vector<FolderEntry> entries;  ///< folders, then files, each sorted by name
  std::string error;                 ///< why the folder could not be read (wholly or in part)
};

/// `folder`'s subfolders and its regular files whose extension, in lower case, is one of
/// `extensions` (lower case, with the dot: ".json"). Hidden entries (a leading '.') and entries whose type cannot be read
/// (broken links, no permission) are left out; an unreadable folder gives `error` and what was
/// read before it. Never throws.
FolderListing list_folder(const std::filesystem::path& folder,
                          const std::vector<std::string>& extensions);

/// `name` as valid UTF-8: bytes that are not part of a well-formed UTF-8 sequence become \xNN.
std::string display_name(const std::string& name);

/// The file a typed name means in the dialog showing `folder`: an absolute path as it is, else the
/// name under `folder`; "~/" is not expanded. Empty for an empty name.
std::filesystem::path resolve_typed(const std::filesystem::path& folder, const std::string& typed);

}  // namespace kaskad::editor
