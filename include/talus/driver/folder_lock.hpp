#pragma once
// One run at a time in an output folder. Two runs writing into one folder (a batch job queued again
// while its first copy still runs, a command typed twice) would delete and rewrite each other's
// frames and histories; the second is refused before it touches anything.
#include <filesystem>

namespace talus {

/// An exclusive claim on an output folder: an flock(2) on DIR/.talus.lock, held while the object
/// lives and released by the kernel when the process ends, however it ends (so a killed run leaves
/// no stale lock, only the unlocked file). The file holds the holder's pid and host, for the
/// refusal's message, and is removed when the object goes. On a file system that cannot lock, the
/// run goes on unguarded.
class FolderLock {
 public:
  /// Creates the folder if needed and takes the lock. Throws an input Error naming the holder when
  /// another process holds it, an io Error when the lock file cannot be made.
  explicit FolderLock(const std::filesystem::path& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace talus
