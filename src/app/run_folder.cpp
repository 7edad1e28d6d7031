#include "run_folder.hpp"

#include "commands.hpp"

#include "host_info.hpp"

#include "talus/core/error.hpp"
#include "talus/io/checkpoint.hpp"

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string_view>

namespace talus::app {

namespace fs = std::filesystem;

namespace {

/// The folder's run.json, or null when there is none that reads as a record.
nlohmann::json folder_record(const fs::path& dir) {
  std::ifstream in(dir / "run.json");
  if (!in) return nullptr;
  nlohmann::json record = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  return record.is_object() ? record : nlohmann::json(nullptr);
}

std::string record_status(const nlohmann::json& record) {
  if (!record.is_object()) return "";
  const auto it = record.find("status");
  return it != record.end() && it->is_string() ? it->get<std::string>() : "";
}

/// A number at `pointer` in the record, if it is one.
std::optional<double> record_number(const nlohmann::json& record, const char* pointer) {
  const nlohmann::json::json_pointer at(pointer);
  if (!record.is_object() || !record.contains(at) || !record.at(at).is_number()) return std::nullopt;
  return record.at(at).get<double>();
}

/// What a status says of the run that left it, after "holds ".
std::string unfinished_run(const std::string& status) {
  if (status == "interrupted") return "an interrupted run";
  if (status == "unstable") return "a run a stability guard stopped";
  if (status == "failed") return "a failed run";
  if (status == "running" || status == "ended_unrecorded") return "a run that ended without finishing its record (killed?)";
  return fmt::format("a run that did not complete (run.json: \"{}\")", status);
}

}  // namespace

void require_no_unfinished_run(const fs::path& dir, bool overwrite) {
  if (overwrite) return;
  const fs::path checkpoint = dir / "checkpoint.h5";
  std::error_code ec;
  if (!fs::is_regular_file(checkpoint, ec)) return;
  const nlohmann::json record = folder_record(dir);
  const std::string status = record_status(record);
  if (status.empty() || status == "completed") return;
  const auto at = checkpoint_time_and_step(checkpoint.string());
  // The scene to resume with: the one the record names when it is still there, else the resolved
  // copy the run wrote beside its checkpoint (a restart may read it, run_command.cpp).
  std::string scene = (dir / "scene.json").string();
  if (const nlohmann::json::json_pointer file("/scene/file"); record.contains(file) && record.at(file).is_string() &&
                                                              fs::is_regular_file(record.at(file).get<std::string>(), ec))
    scene = record.at(file).get<std::string>();
  throw input_error(fmt::format(
      "output folder {} holds {}, whose {} (t = {}) a fresh run would delete; resume it with: {} run {} --restart {}; "
      "or give --overwrite to start afresh there",
      dir.string(), unfinished_run(status), checkpoint.filename().string(),
      at ? fmt::format("{:.6g} s, step {}", at->first, at->second) : std::string("unreadable"), program_word(),
      shell_word(scene),
      shell_word(checkpoint.string())));
}

void require_checkpoint_file(const std::string& restart_path) {
  std::error_code ec;
  if (fs::exists(restart_path, ec)) return;  // (read_checkpoint says what is wrong with one that is there)
  fs::path folder = fs::path(restart_path).parent_path();
  if (folder.empty()) folder = ".";
  const nlohmann::json record = folder_record(folder);
  if (record_status(record) == "completed")
    throw input_error(fmt::format(
        "cannot open checkpoint {}: no such file; the run in {} completed (run.json), and a completed run writes no "
        "checkpoint unless output.checkpoint_interval is set: run the scene again with a later time.end (and an "
        "output.checkpoint_interval to be able to extend it later)",
        restart_path, folder.string()));
  throw input_error(fmt::format("cannot open checkpoint {}: no such file", restart_path));
}

std::optional<std::string> rewind_warning(const fs::path& dir, double resume_time, std::size_t kept_frames) {
  const nlohmann::json record = folder_record(dir);
  if (record_status(record) != "completed") return std::nullopt;
  const std::optional<double> end = record_number(record, "/end/time");
  if (!end || !(*end > resume_time)) return std::nullopt;
  const std::optional<double> frames = record_number(record, "/end/frames_in_series");
  std::string replaced = "its later frames";
  if (frames && *frames > double(kept_frames)) {
    const auto last = static_cast<std::size_t>(*frames) - 1;
    replaced = last == kept_frames ? fmt::format("frame {}", kept_frames)
                                   : fmt::format("frames {} to {}", kept_frames, last);
  } else if (frames) {
    replaced = "no frame";
  }
  return fmt::format(
      "resuming from t = {:.6g} s, before the end of the completed run in {} (t = {:.6g} s): the run goes on from the "
      "checkpoint and replaces {} and the history rows after t = {:.6g} s",
      resume_time, dir.string(), *end, replaced, resume_time);
}

std::optional<std::string> older_checkpoint_note(const fs::path& dir, double end_time) {
  const auto at = checkpoint_time_and_step((dir / "checkpoint.h5").string());
  if (!at || !(at->first < end_time)) return std::nullopt;
  return fmt::format(
      "talus: checkpoint.h5 holds t = {:.6g} s (step {}), written before the end (t = {:.6g} s); resuming from it "
      "reruns from there",
      at->first, at->second, end_time);
}

std::optional<std::string> restart_changes_line(const std::vector<std::string>& changed) {
  if (changed.empty()) return std::nullopt;
  // (only another time step changes the bits of what is computed; another end clips the last step)
  const bool steps_change = std::any_of(changed.begin(), changed.end(),
                                        [](const std::string& c) { return c.rfind("time.courant:", 0) == 0; });
  return fmt::format("talus: restart with {} changed: {}; the run goes on with this scene's{}",
                     changed.size() == 1 ? std::string("1 key") : fmt::format("{} keys", changed.size()),
                     fmt::join(changed, "; "),
                     steps_change ? " (another time.courant: other time steps, other results than without the change)" : "");
}

std::string run_help_footer() {
  return "Files written in the output folder (README.md, \"What a run writes\"):\n"
         "  particles.pvd, frames/particles_NNNNNN.vtu (.pvtu and one piece per rank under mpirun)  the ParaView series\n"
         "  energy.csv    the energy history        scene.json  the scene as run (resolved)\n"
         "  run.json      the run's record: build, command, host, status (running, completed, interrupted, unstable, failed)\n"
         "  checkpoint.h5 the state to resume from (output.checkpoint_interval, a signal, --stop-after, an instability;\n"
         "                checkpoint_earlier.h5 the one before it after an instability)\n"
         "  runout.csv, runout.json, deposit.csv  with diagnostics.runout;  terrain.vtu  on a terrain grid\n"
         "A fresh run clears these files; one into a folder whose unfinished run left a checkpoint is refused unless\n"
         "--overwrite is given.\n"
         "Exit codes:\n"
         "  0    the run completed (or stopped at time.max_steps, or every particle left the grid)\n"
         "  2    bad input (scene, options, output folder, memory) or an I/O error, with one line on stderr\n"
         "  3    a stability guard stopped the run; its last good state is written as a frame and a checkpoint\n"
         "  4    an internal error\n"
         "  75   stopped by --stop-after, with a checkpoint\n"
         "  128+N  stopped by signal N (130 Ctrl-C, 143 SIGTERM, 138 SIGUSR1), with a checkpoint";
}

std::string shell_word(const std::string& path) {
  const bool plain = !path.empty() && std::all_of(path.begin(), path.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::string_view("_-./+:=,@%").find(c) != std::string_view::npos;
  });
  if (plain) return path;
  std::string quoted = "'";
  for (char c : path) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string program_word() {
  const std::vector<std::string>& words = command_line();
  if (words.empty() || words[0].find('/') == std::string::npos) return "talus";
  return shell_word(words[0]);
}

}  // namespace talus::app
