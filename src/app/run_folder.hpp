#pragma once
// What a run's output folder already holds of an earlier run (its run.json and checkpoint.h5), read
// before a run clears or extends it: a fresh run into the folder of an unfinished one deleted its
// checkpoint without a word, and a restart from a periodic checkpoint older than a completed run's
// end rewound it silently.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace talus::app {

/// Refuses (input Error, one line) a fresh run into `dir` when its run.json says the run there did
/// not finish (interrupted, unstable, failed, or still "running": killed) and its checkpoint.h5 is
/// there: the line names the checkpoint's time and the command that resumes it. `--overwrite`
/// (`overwrite`) allows it.
void require_no_unfinished_run(const std::filesystem::path& dir, bool overwrite);

/// Refuses (input Error) a --restart whose checkpoint file is not there, saying why; when the
/// folder's run.json says its run completed: that a completed run writes no checkpoint unless
/// output.checkpoint_interval is set.
void require_checkpoint_file(const std::string& restart_path);

/// A restart into the checkpoint's own folder (`dir`) from a checkpoint older than the end the
/// folder's completed run reached: the warning that names the frames the run replaces (those from
/// `kept_frames` on), or nothing.
std::optional<std::string> rewind_warning(const std::filesystem::path& dir, double resume_time,
                                          std::size_t kept_frames);

/// A completed run whose folder holds a checkpoint.h5 written before its end (a periodic one): the
/// closing line that says so, or nothing.
std::optional<std::string> older_checkpoint_note(const std::filesystem::path& dir, double end_time);

/// The info line of a restart that changes keys a restart may change (restart_changes), or nothing:
/// printed once the restart is accepted (before its refusal, it read as if the run had started).
std::optional<std::string> restart_changes_line(const std::vector<std::string>& changed);



/// What `talus run --help` says after the options: the files a run writes and its exit codes.
std::string run_help_footer();

/// A path as a shell word: as it is when it holds only characters no shell reads specially, else in
/// single quotes (a resume line is copied into a shell; a path with a space split in two there).
std::string shell_word(const std::string& path);
/// The program as a line to copy names it: the path it was started by when that is one
/// (`build/talus`, as the README runs it), else `talus` (found on PATH). A resume line that said
/// `talus run …` was "command not found" to a user who had started `build/talus`.
std::string program_word();

}  // namespace talus::app
