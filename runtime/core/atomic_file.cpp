#include "runtime/core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <utility>

#include "runtime/core/file_io.h"

namespace kaskad {
namespace fs = std::filesystem;
namespace {

std::string errno_text(int err) { return std::strerror(err); }

/// mkstemps() in the target's folder: ".NAME.XXXXXX.EXT" (hidden, same extension). Returns the fd
/// (or -1 with errno set) and fills `temp`.
int make_temp(const fs::path& target, fs::path& temp) {
  const std::string ext = target.extension().string().substr(0, 32);
  // The stem is shortened so that a long (but valid) target name still has a valid temp name.
  std::string pattern = (folder_of(target) / (std::string(".") + target.stem().string().substr(0, 64) +
                                              ".kaskad-XXXXXX" + ext))
                            .string();
  const int fd = ::mkstemps(pattern.data(), int(ext.size()));
  if (fd >= 0) temp = pattern;
  return fd;
}

/// The permissions the output should get: the previous file's, else 0666 minus the umask
/// (mkstemp makes 0600 files).
mode_t output_mode(const fs::path& target) {
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0 && S_ISREG(st.st_mode)) return st.st_mode & 07777;
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return 0666 & ~mask;
}

/// fsync + close + rename over the target + fsync of the folder. Removes the temp on failure.
Status publish(int fd, const fs::path& temp, const fs::path& target) {
  const std::string name = target.string();
  auto fail = [&](const std::string& what, int err) -> Status {
    if (fd >= 0) ::close(fd);
    ::unlink(temp.c_str());
    return Error{name, "", what + ": " + errno_text(err) + " (the previous file, if any, is unchanged)"};
  };
  (void)::fchmod(fd, output_mode(target));
  if (::fsync(fd) != 0) return fail("cannot flush the data to disk", errno);
  const int closed = ::close(fd);
  fd = -1;
  if (closed != 0) return fail("write failed on close", errno);
  if (::rename(temp.c_str(), target.c_str()) != 0) return fail("cannot replace the file", errno);
  // Make the rename itself durable; a folder that cannot be synced is not an error.
  const int dir = ::open(folder_of(target).c_str(), O_RDONLY | O_DIRECTORY);
  if (dir >= 0) {
    (void)::fsync(dir);
    ::close(dir);
  }
  return {};
}

/// The file a write to `path` lands in: through symbolic links (relative ones from the link's
/// folder), so an output named by a link replaces the file it points to and the link stays.
/// A dangling link's target is created; a loop is left to the checks to report.
fs::path through_links(const fs::path& path) {
  fs::path p = path;
  for (int hops = 0; hops < 40; ++hops) {  // the kernel's own limit (ELOOP)
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return p;
    const fs::path to = fs::read_symlink(p, ec);
    if (ec) return p;
    p = to.is_absolute() ? to : folder_of(p) / to;
  }
  return p;
}

/// Why files cannot be made in `dir` (empty when they can).
std::string folder_problem(const fs::path& dir) {
  std::error_code ec;
  const auto st = fs::status(dir, ec);
  if (!fs::exists(st))
    return std::string("folder '") + dir.string() + "' does not exist (kaskad does not create it; make it first)";
  if (!fs::is_directory(st)) return std::string("'") + dir.string() + "' is not a folder";
  // Root passes permission checks, so try for real: /proc or a read-only mount refuse here.
  fs::path temp;
  const int fd = make_temp(dir / "probe", temp);
  if (fd < 0) return std::string("cannot create files in folder '") + dir.string() + "': " + errno_text(errno);
  ::close(fd);
  ::unlink(temp.c_str());
  return {};
}

}  // namespace

Status check_output_folder(const fs::path& dir) {
  if (const std::string problem = folder_problem(dir); !problem.empty())
    return Error{dir.string(), "", problem};
  return {};
}

Status check_output_folder_to_make(const fs::path& dir) {
  if (dir.empty()) return Error{"", "", "empty output folder name"};
  std::error_code ec;
  if (fs::exists(fs::symlink_status(dir, ec)) || fs::exists(dir, ec)) return check_output_folder(dir);
  // "a/b/" names b: its parent is a.
  const fs::path named = dir.has_filename() ? dir : dir.parent_path();
  const fs::path parent = folder_of(named);
  if (!fs::exists(parent, ec))
    return Error{dir.string(), "", "cannot make this folder: its parent '" + parent.string() +
                                       "' does not exist (kaskad makes only the folder named)"};
  if (const std::string problem = folder_problem(parent); !problem.empty())
    return Error{dir.string(), "", "cannot make this folder: " + problem};
  return {};
}

Status check_output_path(const fs::path& path) {
  const std::string name = path.string();
  if (path.empty()) return Error{"", "", "empty output file name"};
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (fs::is_directory(st) || path.filename().empty() || path.filename() == "." ||
      path.filename() == "..")
    return Error{name, "", "is a folder, not a file: name the file to write"};
  if (path.filename().string().size() > NAME_MAX)
    return Error{name, "", "file name longer than " + std::to_string(NAME_MAX) + " bytes"};
  if (fs::exists(st) && !fs::is_regular_file(st))
    return Error{name, "", "exists and is not a regular file (a device, pipe or socket); "
                           "kaskad replaces only regular files"};
  if (const std::string problem = folder_problem(folder_of(path)); !problem.empty())
    return Error{name, "", std::string("cannot write here: ") + problem};
  return {};
}

Status write_file_atomic(const fs::path& named, const void* data, std::size_t size) {
  const fs::path path = through_links(named);
  const std::string name = path.string();
  KASKAD_TRY(check_output_path(path));
  fs::path temp;
  const int fd = make_temp(path, temp);
  if (fd < 0) return Error{name, "", "cannot create a temporary file beside it: " + errno_text(errno)};
  const auto* bytes = static_cast<const char*>(data);
  std::size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, bytes + written, size - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      ::unlink(temp.c_str());
      return Error{name, "", "write failed after " + std::to_string(written) + " of " +
                                 std::to_string(size) + " bytes: " + errno_text(err) +
                                 " (the previous file, if any, is unchanged)"};
    }
    written += std::size_t(n);
  }
  return publish(fd, temp, path);
}

Result<TempFile> TempFile::create(const fs::path& named) {
  const fs::path target = through_links(named);
  KASKAD_TRY(check_output_path(target));
  fs::path temp;
  const int fd = make_temp(target, temp);
  if (fd < 0)
    return Error{target.string(), "", "cannot create a temporary file beside it: " + errno_text(errno)};
  ::close(fd);
  return TempFile(target, temp);
}

TempFile::TempFile(TempFile&& other) noexcept
    : target_(std::move(other.target_)), temp_(std::move(other.temp_)), done_(other.done_) {
  other.done_ = true;
}

TempFile::~TempFile() {
  if (!done_) ::unlink(temp_.c_str());
}

Status TempFile::commit() {
  done_ = true;
  struct stat st {};
  if (::stat(temp_.c_str(), &st) != 0 || st.st_size == 0) {
    ::unlink(temp_.c_str());
    return Error{target_.string(), "", "the writer produced no data (the previous file, if any, is unchanged)"};
  }
  const int fd = ::open(temp_.c_str(), O_RDWR);
  if (fd < 0) {
    const int err = errno;
    ::unlink(temp_.c_str());
    return Error{target_.string(), "", "cannot reopen the temporary file: " + errno_text(err)};
  }
  return publish(fd, temp_, target_);
}

}  // namespace kaskad
