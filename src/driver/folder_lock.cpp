#include "talus/driver/folder_lock.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace talus {

namespace fs = std::filesystem;

namespace {

/// Whether the open file `fd` is still the one at `path` (a run that ended unlinks its lock file:
/// a lock taken on the unlinked file would claim nothing).
bool still_at(int fd, const fs::path& path) {
  struct stat held {}, named {};
  return ::fstat(fd, &held) == 0 && ::stat(path.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
         held.st_ino == named.st_ino;
}

}  // namespace

FolderLock::FolderLock(const fs::path& dir) : path_(dir / ".talus.lock") {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", dir.string(), ec.message()));
  for (int attempt = 0; attempt < 8; ++attempt) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw io_error(fmt::format("cannot write {}: {}", path_.string(), std::strerror(errno)));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      ::close(fd_);
      fd_ = -1;
      if (error != EWOULDBLOCK) return;  // a file system without locks (some NFS set-ups): run unguarded, as before
      std::ifstream in(path_);
      std::stringstream holder;
      holder << in.rdbuf();
      std::string who = holder.str();
      while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
      throw input_error(fmt::format("output folder {} is in use by another talus run{}; wait for it to end, or "
                                    "choose another folder (--out)",
                                    dir.string(), who.empty() ? "" : " (" + who + ")"));
    }
    if (still_at(fd_, path_)) break;
    ::close(fd_);  // the run before unlinked it as this one locked it: take the new file
    fd_ = -1;
  }
  if (fd_ < 0) return;
  std::array<char, 256> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) host[0] = '\0';
  const std::string who = fmt::format("pid {} on {}\n", ::getpid(), host[0] ? host.data() : "an unknown host");
  // Best effort: the lock is the flock; the text only names its holder in another run's refusal.
  const bool named = ::ftruncate(fd_, 0) == 0 && ::pwrite(fd_, who.data(), who.size(), 0) == ssize_t(who.size());
  (void)named;
}

FolderLock::~FolderLock() {
  if (fd_ < 0) return;
  // Unlinked while still held, then released: a run that ends leaves no file behind (a killed one
  // leaves it, unlocked, for the next run to take).
  ::unlink(path_.c_str());
  ::close(fd_);
}

}  // namespace talus
