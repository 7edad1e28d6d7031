#include "talus/io/atomic_file.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace talus {

void write_file_atomically(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&text](std::ostream& out) { out << text; });
}

void write_file_atomically(const std::string& given_path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // A device, a FIFO or a socket (`-o /dev/null`, `-o /dev/stdout`, a named pipe) is written
  // through: the rename replaced it with a regular file, and as root that was /dev/null for the
  // whole machine. Through a symbolic link the file it names is replaced, and the link kept.
  const fs::file_status target = fs::status(given_path, ec);
  if (fs::exists(target) && !fs::is_regular_file(target) && !fs::is_directory(target)) {
    errno = 0;
    std::ofstream out(given_path, std::ios::binary);
    write(out);
    out.flush();
    if (!out)
      throw io_error(fmt::format("cannot write {}{}", given_path, errno ? std::string(": ") + std::strerror(errno) : ""));
    return;
  }
  std::string path = given_path;
  if (fs::is_symlink(fs::symlink_status(given_path, ec)) && fs::exists(target)) {
    const fs::path resolved = fs::canonical(given_path, ec);
    if (!ec) path = resolved.string();  // (else the link itself is replaced, as before)
  }
  // (the process's own temporary name: two ranks that write one file at once, as a distributed
  // run's ranks that fail together write run.json, each rename a whole file)
  const std::string tmp = path + "." + std::to_string(::getpid()) + ".tmp";
  {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    write(out);
    out.flush();
    if (!out) {
      const int error = errno;  // (the stream's failure leaves the system's reason in errno)
      out.close();
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);  // a partial or empty file was left behind
      throw io_error(fmt::format("cannot write {}{}", path, error ? std::string(": ") + std::strerror(error) : ""));
    }
  }
  rename_into_place(tmp, path);
}

void rename_into_place(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw io_error(fmt::format("cannot write {}: {}", path, ec.message()));
}

}  // namespace talus
