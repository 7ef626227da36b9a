// The file dialog's folder logic (editor/file_dialog.h): what a folder lists, in what order, and
// that odd entries (broken links, names that are not UTF-8, unreadable folders) are handled.
#include "editor/file_dialog.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "tests/test_tmp.h"

using namespace kaskad::editor;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path d = kaskad::testing_util::test_tmp() / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void touch(const fs::path& p) {
  std::ofstream(p, std::ios::binary) << "{}";
}

std::vector<std::string> labels(const FolderListing& l) {
  std::vector<std::string> out;
  for (const auto& e : l.entries) out.push_back(e.label + (e.folder ? "/" : ""));
  return out;
}

}  // namespace

TEST(FileDialog, ListsFoldersThenMatchingFilesSorted) {
  const fs::path d = fresh_dir("plain");
  fs::create_directory(d / "scenes");
  fs::create_directory(d / "a_models");
  touch(d / "b.json");
  touch(d / "A.JSON");  // the extension without case
  touch(d / "notes.txt");
  touch(d / "model.gltf");
  touch(d / ".hidden.json");
  fs::create_directory(d / "folder.json");  // a folder, whatever its name
  const FolderListing l = list_folder(d, {".json"});
  EXPECT_EQ(l.error, "");
  EXPECT_EQ(labels(l),
            (std::vector<std::string>{"a_models/", "folder.json/", "scenes/", "A.JSON", "b.json"}));
  EXPECT_EQ(labels(list_folder(d, {".gltf", ".glb"})),
            (std::vector<std::string>{"a_models/", "folder.json/", "scenes/", "model.gltf"}));
  EXPECT_EQ(list_folder(d, {".json"}).entries.back().path, d / "b.json");
}

TEST(FileDialog, OddEntriesAreLeftOutOrEscapedNeverFatal) {
  const fs::path d = fresh_dir("odd");
  fs::create_symlink(d / "nowhere.json", d / "broken.json");  // a broken link: left out
  fs::create_directory(d / "real");
  fs::create_directory_symlink(d / "real", d / "linked");  // a link to a folder: a folder
  touch(d / "real.json");
  fs::create_symlink(d / "real.json", d / "alias.json");         // a link to a file: a file
  const std::string bad = std::string("caf\xE9") + "\xFF.json";  // Latin-1 bytes, not UTF-8
  touch(d / bad);
  touch(d / "caf\xC3\xA9.json");  // UTF-8: shown as it is
  const FolderListing l = list_folder(d, {".json"});
  EXPECT_EQ(l.error, "");
  // Sorted by the names' bytes: 0xC3 (UTF-8 'é') before 0xE9 (Latin-1 'é').
  EXPECT_EQ(labels(l),
            (std::vector<std::string>{"linked/", "real/", "alias.json", "caf\xC3\xA9.json",
                                      "caf\\xE9\\xFF.json", "real.json"}));
  // The path keeps the bytes: the file opens.
  const auto it = std::find_if(l.entries.begin(), l.entries.end(), [](const FolderEntry& e) {
    return e.label == "caf\\xE9\\xFF.json";
  });
  ASSERT_NE(it, l.entries.end());
  EXPECT_TRUE(std::ifstream(it->path).good());
}

TEST(FileDialog, UnreadableFoldersAreErrorsNotCrashes) {
  const fs::path d = fresh_dir("errors");
  FolderListing l = list_folder(d / "missing", {".json"});
  EXPECT_TRUE(l.entries.empty());
  EXPECT_NE(l.error.find("cannot read"), std::string::npos) << l.error;
  EXPECT_NE(l.error.find("missing"), std::string::npos) << l.error;
  touch(d / "file.json");
  l = list_folder(d / "file.json", {".json"});  // a file is not a folder
  EXPECT_NE(l.error.find("cannot read"), std::string::npos) << l.error;
  if (geteuid() != 0) {  // root reads any folder
    fs::create_directory(d / "locked");
    fs::permissions(d / "locked", fs::perms::none);
    l = list_folder(d / "locked", {".json"});
    EXPECT_NE(l.error.find("ermission denied"), std::string::npos) << l.error;
    fs::permissions(d / "locked", fs::perms::owner_all);
  }
}

TEST(FileDialog, DisplayNamesAreValidUtf8) {
  EXPECT_EQ(display_name("plain.json"), "plain.json");
  EXPECT_EQ(display_name("\xE2\x82\xAC.json"), "\xE2\x82\xAC.json");  // the euro sign
  EXPECT_EQ(display_name("\xC0\xAF"), "\\xC0\\xAF");                  // an overlong '/'
  EXPECT_EQ(display_name("\xED\xA0\x80"), "\\xED\\xA0\\x80");         // a surrogate
  EXPECT_EQ(display_name("\xE2\x82"), "\\xE2\\x82");                  // cut short
  EXPECT_EQ(display_name("a\nb"), "a\\x0Ab");                         // a control character
}

TEST(FileDialog, TypedNamesResolveAgainstTheFolder) {
  EXPECT_EQ(resolve_typed("/scenes", "a.json"), fs::path("/scenes/a.json"));
  EXPECT_EQ(resolve_typed("/scenes", "sub/a.json"), fs::path("/scenes/sub/a.json"));
  EXPECT_EQ(resolve_typed("/scenes", "/tmp/a.json"), fs::path("/tmp/a.json"));
  EXPECT_EQ(resolve_typed("/scenes", ""), fs::path());
}
