#pragma once
// Every output file complete or absent: a file is written under a temporary name and renamed into
// place, so that a crash, a full disk or a killed job never leaves half a file under the final name.
#include <functional>
#include <ostream>
#include <string>

namespace talus {

/// Write `text` to `path` through a temporary file and a rename (atomic on POSIX file systems).
void write_file_atomically(const std::string& path, const std::string& text);

/// As above, with what `write` puts into the stream: a large text (a work record) goes to the file
/// without a copy in memory. The stream's failure (a full disk) is an io_error naming the file.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// The last step of an atomic write: the temporary file takes the final name. A failure is an
/// io_error naming the file (not a filesystem_error, which would reach the user as an internal error).
void rename_into_place(const std::string& tmp, const std::string& path);

}  // namespace talus
