// The file dialog's folder logic (`kaskad edit`: Open, Save as, Import model): listing a folder and
// resolving a typed name, and the dialog's state. Pure (no window, no ImGui); the dialog itself is
// drawn in file_dialog_panel.cpp.
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

// The file dialog's state: what it is for, the folder shown and the name typed.
struct FileDialog {
  enum class Purpose { open, save_as, import };
  Purpose purpose = Purpose::open;
  bool visible = false;           ///< shown; the operation's success or Cancel ends it
  bool appearing = false;         ///< open the popup on the next frame
  std::filesystem::path folder;   ///< absolute
  FolderListing listing;          ///< of `folder`, read when it changes (and on refresh)
  char name[1024] = "";           ///< typed, or the label of the entry clicked
  std::filesystem::path picked;   ///< the entry clicked (its bytes, whatever its label)
  std::filesystem::path replace;  ///< save as: the existing file the user was asked about
  std::string error;              ///< the last refusal (an operation's error), shown in the dialog

  const char* title() const {
    return purpose == Purpose::open ? "Open scene###file_dialog"
           : purpose == Purpose::save_as ? "Save scene as###file_dialog"
                                         : "Import model###file_dialog";
  }
  std::vector<std::string> extensions() const {
    if (purpose == Purpose::import) return {".gltf", ".glb"};
    return {".json"};
  }
  /// Shows `dir` (made absolute and normal), listed afresh; forgets the entry picked and the error.
  void enter(const std::filesystem::path& dir);
};

}  // namespace kaskad::editor
