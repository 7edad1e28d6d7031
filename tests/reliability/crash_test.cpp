// The talus program under interruption: SIGTERM writes a checkpoint and `--restart` finishes the
// run with output identical to an uninterrupted run; SIGKILL at random moments leaves every listed
// frame, the energy history and the last checkpoint readable, and the restart continues from it.
#include "reliability_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/io/checkpoint.hpp"

#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <map>
#include <random>
#include <regex>
#include <thread>

namespace talus {
namespace crash_test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// Runs talus with `args` in a child process, its standard output and error both into `log` (as
/// `talus ... > log 2>&1`; by default nowhere).
pid_t spawn(const std::vector<std::string>& args, const fs::path& log = "/dev/null") {
  const pid_t pid = fork();
  if (pid == 0) {
    const int file = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(file, 1);
    dup2(file, 2);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(TALUS_BINARY));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(TALUS_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}

/// Exit code, or 128 + signal.
int wait_for(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int run_talus(const std::vector<std::string>& args) { return wait_for(spawn(args)); }

/// The shell's `command`: its exit code and its standard output.
std::pair<int, std::string> run_shell(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  std::string text;
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, pipe)) text += buffer;
  const int status = pclose(pipe);
  return {WEXITSTATUS(status), text};
}

/// `talus ARGS` (as a shell splits them), its standard output and error together.
std::pair<int, std::string> run_captured(const std::string& args) {
  return run_shell(std::string(TALUS_BINARY) + " " + args + " 2>&1");
}

/// Runs the scene uninterrupted once per test binary: the reference output.
struct Reference {
  fs::path root, scene, out;
  double seconds = 0.0;
};

const Reference& reference() {
  // The reference's folder, and every test's output under it, goes when the test binary exits: each
  // run of the tests would otherwise leave some 4 MB in the temporary folder.
  static const test::ScratchDir root("rel_crash_ref");
  static const Reference r = [] {
    Reference ref;
    ref.root = root.path();
    ref.scene = ref.root / "scene.json";
    std::ofstream(ref.scene) << test::small_slide_json(0.4, 0.02);
    ref.out = ref.root / "out";
    const auto t0 = Clock::now();
    EXPECT_EQ(run_talus({"run", ref.scene.string(), "--out", ref.out.string(), "--quiet", "--threads", "1"}), 0);
    ref.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return ref;
  }();
  return r;
}

/// A fresh copy of the reference's output folder: ref.root / `name`, an earlier copy replaced.
fs::path fresh_copy_of_reference(const Reference& ref, const std::string& name) {
  const fs::path copy = ref.root / name;
  fs::remove_all(copy);
  fs::copy(ref.out, copy, fs::copy_options::recursive);
  return copy;
}

/// The output of a restarted run equals the uninterrupted one: every frame, the index and the
/// energy history, byte for byte.
void expect_same_output(const fs::path& out, const fs::path& ref) {
  EXPECT_EQ(test::read_text(out / "particles.pvd"), test::read_text(ref / "particles.pvd"));
  EXPECT_EQ(test::read_text(out / "energy.csv"), test::read_text(ref / "energy.csv"));
  const auto frames = test::pvd_frames(ref / "particles.pvd");
  for (const auto& f : frames)
    EXPECT_TRUE(test::read_text(f) == test::read_text(out / "frames" / f.filename())) << f.filename() << " differs";
}

/// The run's record, run.json (app/run_record.hpp).
nlohmann::json read_record(const fs::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "run.json")); }

bool wait_for_file(const fs::path& path, pid_t pid, double timeout) {
  const auto t0 = Clock::now();
  while (!fs::exists(path)) {
    int status;
    if (waitpid(pid, &status, WNOHANG) == pid) return false;  // finished (reaped)
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return true;
}

TEST(Crash, SigtermWritesACheckpointAndRestartMatchesAnUninterruptedRun) {
  const Reference& ref = reference();
  test::expect_readable_run_folder(ref.out);
  const fs::path out = ref.root / "term";
  fs::remove_all(out);
  const pid_t pid = spawn({"run", ref.scene.string(), "--out", out.string(), "--quiet", "--threads", "1"});
  ASSERT_TRUE(wait_for_file(out / "checkpoint.h5", pid, 60.0));
  std::this_thread::sleep_for(std::chrono::duration<double>(0.3 * ref.seconds));
  kill(pid, SIGTERM);
  const int code = wait_for(pid);
  ASSERT_TRUE(code == 128 + SIGTERM || code == 0) << code;
  if (code == 0) GTEST_SKIP() << "the run finished before the signal arrived";
  const Checkpoint c = read_checkpoint((out / "checkpoint.h5").string());
  EXPECT_GT(c.solver.step, 0);
  test::expect_readable_run_folder(out);
  const nlohmann::json stopped = read_record(out);
  EXPECT_EQ(stopped.at("status"), "interrupted");
  EXPECT_EQ(stopped.at("message"), "stopped by signal 15 after writing a checkpoint");
  EXPECT_EQ(stopped.at("end").at("step").get<std::int64_t>(), c.solver.step);
  EXPECT_EQ(stopped.at("end").at("checkpoint"), (out / "checkpoint.h5").string());
  ASSERT_EQ(run_talus({"run", ref.scene.string(), "--restart", (out / "checkpoint.h5").string(), "--quiet", "--threads", "1"}), 0);
  expect_same_output(out, ref.out);
  // The resumed run's record names its checkpoint and keeps the first part's.
  const nlohmann::json resumed = read_record(out);
  EXPECT_EQ(resumed.at("status"), "completed");
  EXPECT_EQ(resumed.at("restart").at("step").get<std::int64_t>(), c.solver.step);
  EXPECT_EQ(resumed.at("start").at("step").get<std::int64_t>(), c.solver.step);
  EXPECT_EQ(resumed.at("end").at("step"), read_record(ref.out).at("end").at("step"));
  ASSERT_EQ(resumed.at("earlier_parts").size(), 1u);
  EXPECT_EQ(resumed.at("earlier_parts")[0], stopped);
}

// While a run goes on, its record says how far it got ("progress", at the progress lines' cadence
// even with --quiet), so a killed run's record does too; the end replaces it.
TEST(Crash, TheRecordOfARunningRunSaysHowFarItGot) {
  const test::ScratchDir dir("rel_heartbeat");
  std::ofstream(dir / "s.json") << test::small_slide_json(3.0, 0.0);
  const fs::path out = dir / "out";
  const pid_t pid = spawn({"run", (dir / "s.json").string(), "--out", out.string(), "--quiet", "--threads", "1",
                           "--progress-every", "0.1"});
  nlohmann::json seen;
  const auto t0 = Clock::now();
  while (!seen.contains("progress") && std::chrono::duration<double>(Clock::now() - t0).count() < 60.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::ifstream in(out / "run.json");
    if (in) seen = nlohmann::json::parse(in, nullptr, false);
  }
  kill(pid, SIGKILL);
  const int code = wait_for(pid);
  ASSERT_TRUE(seen.contains("progress")) << seen.dump();
  if (code == 0) GTEST_SKIP() << "the run ended before the kill";
  EXPECT_EQ(seen.at("status"), "running");
  EXPECT_GT(seen.at("progress").at("step").get<std::int64_t>(), 0);
  EXPECT_GT(seen.at("progress").at("time").get<double>(), 0.0);
  EXPECT_EQ(seen.at("progress").at("updated").get<std::string>().size(), 20u);
  const nlohmann::json killed = read_record(out);  // whole after the kill, and no earlier than what was seen
  EXPECT_EQ(killed.at("status"), "running");
  EXPECT_GE(killed.at("progress").at("step").get<std::int64_t>(), seen.at("progress").at("step").get<std::int64_t>());
}

// One run at a time in a folder (driver/folder_lock.hpp): a second run into the folder of one that
// is running is refused with one line naming the holder, before it touches anything; once the
// first has ended, however it ended, the folder is free again.
TEST(Crash, ASecondRunIntoTheFolderOfARunningOneIsRefused) {
  const test::ScratchDir dir("rel_folder_lock");
  std::ofstream(dir / "s.json") << test::small_slide_json(3.0, 0.0);
  const fs::path out = dir / "out";
  const pid_t pid = spawn({"run", (dir / "s.json").string(), "--out", out.string(), "--quiet", "--threads", "1"});
  // (scene.json is written whole, under a temporary name, once the run has started)
  ASSERT_TRUE(wait_for_file(out / "scene.json", pid, 60.0));
  const std::string scene_before = test::read_text(out / "scene.json");
  const auto [code, text] = run_captured("run " + (dir / "s.json").string() + " --out " + out.string() + " --quiet --threads 1");
  const bool first_still_ran = ::kill(pid, SIGKILL) == 0;
  wait_for(pid);
  if (!first_still_ran) GTEST_SKIP() << "the first run ended before the second started";
  EXPECT_EQ(code, 2) << text;
  EXPECT_EQ(text.rfind("talus: error: output folder " + out.string() + " is in use by another talus run (pid " +
                           std::to_string(pid) + " on ", 0),
            0u) << text;
  const std::string tail = "); wait for it to end, or choose another folder (--out)\n";
  EXPECT_TRUE(text.size() > tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_EQ(test::read_text(out / "scene.json"), scene_before);  // nothing of the first run's was cleared
  EXPECT_TRUE(fs::exists(out / "energy.csv"));
  // Killed, the first run holds nothing: the folder takes a new run.
  const auto [again, again_text] = run_captured("run " + (dir / "s.json").string() + " --out " + out.string() +
                                                " --quiet --threads 1 --stop-after 0.05s");
  EXPECT_TRUE(again == 75 || again == 0) << again_text;
}

// --stop-after (a batch job's time limit) stops as SIGTERM does, with exit code 75: the restart
// then finishes with the uninterrupted run's output.
TEST(Crash, StopAfterWritesACheckpointAndTheRestartMatchesAnUninterruptedRun) {
  const Reference& ref = reference();
  const fs::path out = ref.root / "stop after";  // a space: the resume line quotes it for the shell
  fs::remove_all(out);
  const std::string limit = fmt::format("{:.3f}s", std::max(0.3 * ref.seconds, 0.001));
  const auto [code, text] = run_captured("run " + ref.scene.string() + " --out '" + out.string() +
                                         "' --quiet --threads 1 --stop-after " + limit);
  ASSERT_TRUE(code == 75 || code == 0) << code << text;
  if (code == 0) GTEST_SKIP() << "the run finished within " << limit;
  const Checkpoint c = read_checkpoint((out / "checkpoint.h5").string());
  test::expect_readable_run_folder(out);
  const nlohmann::json stopped = read_record(out);
  EXPECT_EQ(stopped.at("status"), "interrupted");
  EXPECT_EQ(stopped.at("message"), "stopped at its --stop-after time after writing a checkpoint");
  EXPECT_EQ(stopped.at("end").at("step").get<std::int64_t>(), c.solver.step);
  EXPECT_GE(stopped.at("wall_seconds").get<double>(), std::stod(limit));
  // The resume line, as printed, is one shell command that resumes the run, with the program as it
  // was started (a bare `talus` was "command not found" to a user of build/talus)
  const std::string lead = "talus: resume with: " + std::string(TALUS_BINARY) + " ";
  const auto at = text.find(lead);
  ASSERT_NE(at, std::string::npos) << text;
  const std::string resume = text.substr(at + lead.size(), text.find('\n', at) - at - lead.size());
  // (with the --threads the run was started with)
  EXPECT_EQ(resume, "run " + ref.scene.string() + " --restart '" + (out / "checkpoint.h5").string() + "' --threads 1");
  const auto [resumed, resumed_text] = run_captured(resume + " --quiet");
  ASSERT_EQ(resumed, 0) << resumed_text;
  expect_same_output(out, ref.out);
}

TEST(Crash, SigkillAtRandomMomentsLeavesReadableOutputAndTheRestartFinishes) {
  const Reference& ref = reference();
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> when(0.0, 0.8 * ref.seconds);
  int restarted = 0;
  for (int trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const fs::path out = ref.root / ("kill" + std::to_string(trial));
    fs::remove_all(out);
    const pid_t pid = spawn({"run", ref.scene.string(), "--out", out.string(), "--quiet", "--threads", "1"});
    if (!wait_for_file(out / "checkpoint.h5", pid, 60.0)) continue;  // finished first: nothing to test
    std::this_thread::sleep_for(std::chrono::duration<double>(when(rng)));
    kill(pid, SIGKILL);
    wait_for(pid);
    // Everything the killed run left behind is complete.
    test::expect_readable_run_folder(out);
    Checkpoint c;
    ASSERT_NO_THROW(c = read_checkpoint((out / "checkpoint.h5").string()));
    EXPECT_LE(c.run.frame_times.size(), test::pvd_frames(out / "particles.pvd").size());
    nlohmann::json killed;
    ASSERT_NO_THROW(killed = read_record(out));  // whole, whenever the kill came
    // The restart continues from the last checkpoint to the end, and ends where the reference ends.
    ASSERT_EQ(run_talus({"run", ref.scene.string(), "--restart", (out / "checkpoint.h5").string(), "--quiet", "--threads", "1"}), 0);
    expect_same_output(out, ref.out);
    // The killed part's record is kept; one that still said "running" is marked as ended unrecorded.
    const nlohmann::json part = read_record(out).at("earlier_parts").at(0);
    EXPECT_EQ(part.at("status"), killed.at("status") == "running" ? "ended_unrecorded" : killed.at("status")) << part;
    EXPECT_EQ(part.at("started"), killed.at("started"));
    ++restarted;
    fs::remove_all(out);
  }
  EXPECT_GE(restarted, 3);
}

TEST(Crash, RestartRefusesAnotherSceneWithOneLineAndExitTwo) {
  const Reference& ref = reference();
  const fs::path other = ref.root / "other.json";
  // (another end time alone is a change a restart may make: another gravity is not)
  std::ofstream(other) << test::small_slide_json(0.5, 0.02, R"(, "gravity": [0, 0, -9.0])");
  const fs::path out = ref.root / "refuse";
  fs::create_directories(out);
  fs::copy_file(ref.out / "particles.pvd", out / "particles.pvd");
  // Any checkpoint of the reference scene: take one with a short SIGTERM run.
  const pid_t pid = spawn({"run", ref.scene.string(), "--out", (ref.root / "cp").string(), "--quiet"});
  ASSERT_TRUE(wait_for_file(ref.root / "cp" / "checkpoint.h5", pid, 60.0));
  kill(pid, SIGTERM);
  wait_for(pid);
  const auto [code, text] = run_captured("run " + other.string() + " --restart " +
                                         (ref.root / "cp" / "checkpoint.h5").string() + " --out " + out.string());
  EXPECT_EQ(code, 2) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("belongs to another scene"), std::string::npos) << text;
  EXPECT_NE(text.find("/gravity"), std::string::npos) << text;
  // Nothing in the folder was touched.
  EXPECT_EQ(test::read_text(out / "particles.pvd"), test::read_text(ref.out / "particles.pvd"));
  EXPECT_FALSE(fs::exists(out / "energy.csv"));
}

// A fresh run into the folder of an unfinished run (interrupted, unstable, killed) deleted its
// checkpoint and record without a word (the user forgot --restart): refused with the checkpoint's
// time and the command that resumes it, unless --overwrite says to start afresh.
TEST(Crash, AFreshRunIntoAnUnfinishedRunsFolderIsRefusedUnlessOverwrite) {
  const Reference& ref = reference();
  const fs::path out = fresh_copy_of_reference(ref, "unfinished");
  nlohmann::json record = read_record(out);
  record["status"] = "interrupted";
  std::ofstream(out / "run.json") << record.dump(2);
  const std::string record_text = test::read_text(out / "run.json");
  const std::string checkpoint_bytes = test::read_text(out / "checkpoint.h5");
  const Checkpoint c = read_checkpoint((out / "checkpoint.h5").string());
  const auto [code, text] = run_captured("run " + ref.scene.string() + " --out " + out.string() + " --quiet --threads 1");
  EXPECT_EQ(code, 2) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("talus: error: output folder " + out.string() + " holds an interrupted run, whose checkpoint.h5 (t = " +
                      fmt::format("{:.6g} s, step {}", c.solver.time, c.solver.step) + ") a fresh run would delete; resume it "
                      "with: " + TALUS_BINARY + " run " + ref.scene.string() + " --restart " + (out / "checkpoint.h5").string()),
            std::string::npos) << text;
  EXPECT_NE(text.find("--overwrite"), std::string::npos) << text;
  EXPECT_EQ(test::read_text(out / "run.json"), record_text);
  EXPECT_EQ(test::read_text(out / "checkpoint.h5"), checkpoint_bytes);
  // `talus check --out` says so too, and exits as the run would (it said ok and exited 0)
  const auto [checked, check_text] = run_captured("check " + ref.scene.string() + " --out " + out.string());
  EXPECT_EQ(checked, 2) << check_text;
  EXPECT_NE(check_text.find("talus: error: talus run with this --out would stop: output folder " + out.string() +
                            " holds an interrupted run"),
            std::string::npos) << check_text;
  // and with --overwrite, as the run then starts, it says ok
  const auto [overwriting, overwriting_text] = run_captured("check " + ref.scene.string() + " --out " + out.string() + " --overwrite");
  EXPECT_EQ(overwriting, 0) << overwriting_text;
  EXPECT_EQ(overwriting_text.find("would stop"), std::string::npos) << overwriting_text;
  // --overwrite goes with a fresh run only
  const auto [both, both_text] = run_captured("run " + ref.scene.string() + " --out " + out.string() + " --overwrite --restart " +
                                              (out / "checkpoint.h5").string());
  EXPECT_EQ(both, 2) << both_text;
  EXPECT_NE(both_text.find("--restart excludes --overwrite"), std::string::npos) << both_text;
  // With --overwrite the fresh run starts afresh there.
  const auto [again, again_text] = run_captured("run " + ref.scene.string() + " --out " + out.string() + " --quiet --threads 1 --overwrite");
  EXPECT_EQ(again, 0) << again_text;
  EXPECT_EQ(read_record(out).at("status"), "completed");
  expect_same_output(out, ref.out);
  fs::remove_all(out);
}

// A completed run keeps only its last periodic checkpoint, written before its end: the closing lines
// say so, and a restart from it into its own folder (to extend the run, say) warns that it replaces
// the frames after it, where it rewound the run without a word.
TEST(Crash, ACompletedRunsOlderCheckpointIsNamedAndResumingFromItWarns) {
  const Reference& ref = reference();
  // (checkpoints every 0.03 s: the last one, at 0.39 s, before the end at 0.4 s)
  const fs::path scene = ref.root / "every_003.json";
  std::ofstream(scene) << test::small_slide_json(0.4, 0.03);
  const fs::path out = ref.root / "completed", first = ref.root / "completed_first";
  fs::remove_all(out);
  fs::remove_all(first);
  const auto [code, text] = run_captured("run " + scene.string() + " --out " + out.string() + " --quiet --threads 1");
  ASSERT_EQ(code, 0) << text;
  fs::copy(out, first, fs::copy_options::recursive);
  const Checkpoint c = read_checkpoint((out / "checkpoint.h5").string());
  const nlohmann::json end = read_record(out).at("end");
  ASSERT_LT(c.solver.time, end.at("time").get<double>());
  EXPECT_NE(text.find(fmt::format("talus: checkpoint.h5 holds t = {:.6g} s (step {}), written before the end (t = {:.6g} s); "
                                  "resuming from it reruns from there\n",
                                  c.solver.time, c.solver.step, end.at("time").get<double>())),
            std::string::npos) << text;
  const std::size_t frames = end.at("frames_in_series").get<std::size_t>();
  ASSERT_GT(frames, c.run.frame_times.size());
  const auto [resumed, resumed_text] = run_captured("run " + scene.string() + " --restart " + (out / "checkpoint.h5").string() +
                                                    " --quiet --threads 1");
  ASSERT_EQ(resumed, 0) << resumed_text;
  const std::size_t kept = c.run.frame_times.size();
  const std::string replaced = frames - 1 == kept ? fmt::format("frame {}", kept) : fmt::format("frames {} to {}", kept, frames - 1);
  EXPECT_NE(resumed_text.find(fmt::format("talus: warning: resuming from t = {:.6g} s, before the end of the completed run in {} "
                                          "(t = {:.6g} s): the run goes on from the checkpoint and replaces {}",
                                          c.solver.time, out.string(), end.at("time").get<double>(), replaced)),
            std::string::npos) << resumed_text;
  expect_same_output(out, first);
  // A checkpoint that is not there: why, and for a completed run's folder, that it writes none unless asked
  fs::remove(out / "checkpoint.h5");
  const auto [missing, missing_text] = run_captured("run " + scene.string() + " --restart " + (out / "checkpoint.h5").string());
  EXPECT_EQ(missing, 2) << missing_text;
  EXPECT_NE(missing_text.find("cannot open checkpoint " + (out / "checkpoint.h5").string() + ": no such file; the run in " +
                              out.string() + " completed (run.json), and a completed run writes no checkpoint unless "
                              "output.checkpoint_interval is set"),
            std::string::npos) << missing_text;
  fs::remove_all(out);
  fs::remove_all(first);
}

// --record-work into the folder --out makes: it was refused, "the folder ... does not exist".
TEST(Crash, AWorkRecordInsideANewOutputFolderIsAccepted) {
  const Reference& ref = reference();
  const fs::path out = ref.root / "new_with_record";
  fs::remove_all(out);
  const auto [code, text] = run_captured("run " + ref.scene.string() + " --out " + out.string() + " --record-work " +
                                         (out / "work.json").string() + " --quiet --threads 1");
  EXPECT_EQ(code, 0) << text;
  EXPECT_TRUE(fs::exists(out / "work.json"));
  // a folder that is not the one --out makes is still refused
  const auto [other, other_text] = run_captured("run " + ref.scene.string() + " --out " + (ref.root / "new2").string() +
                                                " --record-work " + (ref.root / "nowhere" / "work.json").string() + " --quiet");
  EXPECT_EQ(other, 2) << other_text;
  EXPECT_NE(other_text.find("does not exist"), std::string::npos) << other_text;
  EXPECT_FALSE(fs::exists(ref.root / "new2"));
  fs::remove_all(out);
}

// A restart refused after its scene was accepted (here: into another run's folder) said "restart
// with 1 key changed: ...; the run goes on" before its error: the info line comes once it is accepted.
TEST(Crash, ARefusedRestartSaysOnlyWhyItWasRefused) {
  const Reference& ref = reference();
  const fs::path longer = ref.root / "longer.json";
  std::ofstream(longer) << test::small_slide_json(0.5, 0.02);
  const fs::path other = ref.root / "other_run_for_changes";
  fs::create_directories(other);
  fs::copy_file(ref.out / "energy.csv", other / "energy.csv", fs::copy_options::overwrite_existing);
  const auto [code, text] = run_captured("run " + longer.string() + " --restart " + (ref.out / "checkpoint.h5").string() +
                                         " --out " + other.string() + " --quiet");
  EXPECT_EQ(code, 2) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_EQ(text.find("restart with 1 key changed"), std::string::npos) << text;
  fs::remove_all(other);
}

std::string ref_scene_for_missing(const fs::path& dir) {
  std::ofstream(dir / "ok.json") << test::small_slide_json();
  return (dir / "ok.json").string();
}


// A restart into a folder that holds another run's output (not the checkpoint's own folder) kept
// that run's frames and energy rows below the checkpoint's step: refused, the folder untouched.
TEST(Crash, RestartIntoAnotherRunsFolderIsRefused) {
  const Reference& ref = reference();
  const fs::path other = ref.root / "other_run";
  fs::create_directories(other);
  fs::copy_file(ref.out / "energy.csv", other / "energy.csv", fs::copy_options::overwrite_existing);
  const auto [code, text] = run_captured("run " + ref.scene.string() + " --restart " + (ref.out / "checkpoint.h5").string() +
                                         " --out " + other.string() + " --quiet");
  EXPECT_EQ(code, 2) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("it holds another run's energy.csv"), std::string::npos) << text;
  EXPECT_EQ(test::read_text(other / "energy.csv"), test::read_text(ref.out / "energy.csv"));
  EXPECT_FALSE(fs::exists(other / "particles.pvd"));
  // Resuming from the scene.json a run wrote into its own folder is allowed: it is written back unchanged.
  const fs::path own = fresh_copy_of_reference(ref, "own_scene");
  const auto [resumed, resumed_text] = run_captured("run " + (own / "scene.json").string() + " --restart " +
                                                    (own / "checkpoint.h5").string() + " --quiet --threads 1");
  EXPECT_EQ(resumed, 0) << resumed_text;
  EXPECT_EQ(test::read_text(own / "scene.json"), test::read_text(ref.out / "scene.json"));
  EXPECT_EQ(resumed_text.find("earlier build"), std::string::npos) << resumed_text;
  // The user's own scene file next to a copied checkpoint is not that file: it was replaced by the
  // resolved scene (its notes and layout lost). Refused as a fresh run into its folder is.
  const fs::path mine = ref.root / "my_project";
  fs::remove_all(mine);
  fs::create_directories(mine);
  const std::string my_text = "{ \"comment\": \"my notes\",\n" + test::read_text(ref.scene).substr(1);
  std::ofstream(mine / "scene.json") << my_text;
  fs::copy_file(ref.out / "checkpoint.h5", mine / "checkpoint.h5");
  const auto [refused, refused_text] = run_captured("run " + (mine / "scene.json").string() + " --restart " +
                                                    (mine / "checkpoint.h5").string() + " --quiet --threads 1");
  EXPECT_EQ(refused, 2) << refused_text;
  EXPECT_EQ(std::count(refused_text.begin(), refused_text.end(), '\n'), 1) << refused_text;
  EXPECT_NE(refused_text.find("would replace the scene file"), std::string::npos) << refused_text;
  EXPECT_EQ(test::read_text(mine / "scene.json"), my_text);
  EXPECT_FALSE(fs::exists(mine / "energy.csv"));
}

// Frames written before 2026-12-04 held stress and strain in the solver's Voigt order, without
// component names. A series resumed from such a checkpoint in its own folder mixes the two orders:
// the run says so. (The old frames are made here by taking the names out of the headers.)
TEST(Crash, ResumingASeriesOfFramesInTheOlderTensorOrderWarns) {
  const Reference& ref = reference();
  const fs::path old = fresh_copy_of_reference(ref, "older_frames");
  const std::regex component_name(" ComponentName[0-5]=\"[a-z]+\"");
  for (const fs::path& frame : test::pvd_frames(old / "particles.pvd")) {
    const std::string text = test::read_text(frame);
    const std::size_t data = text.find("<AppendedData");
    ASSERT_NE(data, std::string::npos) << frame;
    const std::string header = std::regex_replace(text.substr(0, data), component_name, "");
    ASSERT_NE(header.size(), data) << frame << ": no component names to take out";
    std::ofstream(frame, std::ios::binary) << header << text.substr(data);
  }
  const auto [code, text] = run_captured("run " + (old / "scene.json").string() + " --restart " +
                                         (old / "checkpoint.h5").string() + " --quiet --threads 1");
  EXPECT_EQ(code, 0) << text;
  EXPECT_NE(text.find("talus: warning: the frames before the checkpoint hold stress and strain in the order of an "
                      "earlier build"), std::string::npos) << text;
  // said once (beside the warning that the copied run had completed past the checkpoint)
  const std::string order = "warning: the frames before the checkpoint";
  EXPECT_EQ(text.find(order), text.rfind(order)) << text;
  EXPECT_NE(text.find("talus: warning: resuming from t = "), std::string::npos) << text;
}

// A restart into its own folder whose frames were partly deleted, or whose energy.csv was lost, went
// on without a word: the series had a gap, the history started at the restart. It still goes on, and
// says so; the intact folder (above) gives no warning.
TEST(Crash, ResumingADamagedOwnFolderSaysWhatItsOutputsLack) {
  const Reference& ref = reference();
  const fs::path damaged = fresh_copy_of_reference(ref, "damaged_own");
  const std::vector<fs::path> frames = test::pvd_frames(damaged / "particles.pvd");
  ASSERT_GE(frames.size(), 3u);
  fs::remove(frames[1]);
  fs::remove(damaged / "energy.csv");
  const auto [code, text] = run_captured("run " + (damaged / "scene.json").string() + " --restart " +
                                         (damaged / "checkpoint.h5").string() + " --quiet --threads 1");
  EXPECT_EQ(code, 0) << text;
  EXPECT_NE(text.find(" frames the checkpoint lists are missing from " + (damaged / "frames").string() +
                      ": the series has gaps there"), std::string::npos) << text;
  EXPECT_NE(text.find((damaged / "energy.csv").string() + " held no row up to the checkpoint's step "), std::string::npos)
      << text;
  // every frame gone, and the history: said too (the test was "a frame is kept", and this said nothing)
  fresh_copy_of_reference(ref, "damaged_own");
  fs::remove_all(damaged / "frames");
  fs::remove(damaged / "energy.csv");
  const auto [all_code, all_text] = run_captured("run " + (damaged / "scene.json").string() + " --restart " +
                                                 (damaged / "checkpoint.h5").string() + " --quiet --threads 1");
  EXPECT_EQ(all_code, 0) << all_text;
  EXPECT_TRUE(std::regex_search(all_text, std::regex("talus: warning: ([0-9]+) of the \\1 frames the checkpoint lists are missing")))
      << all_text;
  EXPECT_NE(all_text.find(" held no row up to the checkpoint's step "), std::string::npos) << all_text;
}

// A run resumed into another folder (--restart ... --out B) writes its frames in B; the earlier ones
// stay in the first part's folder A. Resumed again, in B, the run counted A's frames as missing from
// B and warned that the series had gaps. The checkpoint now says where each frame was written: no
// warning while they are there, and the folder they are missing from when they are not.
TEST(Crash, ResumingAgainInTheFolderOfAResumeElsewhereFindsTheEarlierFrames) {
  const test::ScratchDir root("rel_resume_twice");
  std::ofstream(root / "scene.json") << test::small_slide_json(0.1, 0.02);
  const std::string scene = (root / "scene.json").string();
  // A: stopped after its first step (frame 0 only); B: the rest, with periodic checkpoints
  const auto [stopped, stopped_text] = run_captured("run " + scene + " --out " + (root / "a").string() +
                                                    " --quiet --threads 1 --stop-after 0.001s");
  ASSERT_EQ(stopped, 75) << stopped_text;
  const auto [resumed, resumed_text] = run_captured("run " + scene + " --restart " + (root / "a" / "checkpoint.h5").string() +
                                                    " --out " + (root / "b").string() + " --quiet --threads 1");
  ASSERT_EQ(resumed, 0) << resumed_text;
  ASSERT_TRUE(fs::exists(root / "b" / "checkpoint.h5"));
  const Checkpoint b = read_checkpoint((root / "b" / "checkpoint.h5").string());
  ASSERT_GE(b.run.frame_times.size(), 3u);
  EXPECT_EQ(b.run.frame_folders, (std::vector<std::pair<std::size_t, std::string>>{{0, "../a"}, {1, "."}}));
  EXPECT_FALSE(fs::exists(root / "b" / "frames" / "particles_000000.vtu"));  // frame 0 is A's
  fs::copy(root / "b", root / "b_copy", fs::copy_options::recursive);
  const auto [again, again_text] = run_captured("run " + scene + " --restart " + (root / "b" / "checkpoint.h5").string() +
                                                " --quiet --threads 1");
  EXPECT_EQ(again, 0) << again_text;
  EXPECT_EQ(again_text.find("missing"), std::string::npos) << again_text;
  // A's frame gone: said, naming A's frames folder
  fs::remove(root / "a" / "frames" / "particles_000000.vtu");
  const auto [gap, gap_text] = run_captured("run " + scene + " --restart " + (root / "b_copy" / "checkpoint.h5").string() +
                                            " --quiet --threads 1");
  EXPECT_EQ(gap, 0) << gap_text;
  EXPECT_NE(gap_text.find(fmt::format("1 of the {} frames the checkpoint lists are missing from {}: the series has gaps",
                                      b.run.frame_times.size(), (root / "a" / "frames").string())),
            std::string::npos)
      << gap_text;
}

// Without diagnostics.runout.gate_x the runout is measured from the initial front, runout.csv's
// first row: a resume whose folder lacks it (a resume of a resume into another folder, or here a
// runout.csv removed) measured it from the front at the restart, 22% short on a terrain slide,
// without a word. The checkpoint keeps that row now (b: the same runout.json as the intact folder
// a); one written before it did (c: the row removed from the file) warns.
TEST(Crash, ResumingWithoutTheRunoutRowsFromTheStartKeepsTheGate) {
  const Reference& ref = reference();
  const fs::path root = ref.root / "runout_gate";
  fs::remove_all(root);
  fs::create_directories(root);
  std::ofstream(root / "scene.json") << test::small_slide_json(0.4, 0.02, R"(, "diagnostics": { "runout": {} })");
  // (the run keeps its last periodic checkpoint, near its end)
  ASSERT_EQ(run_talus({"run", (root / "scene.json").string(), "--out", (root / "a").string(), "--quiet", "--threads", "1"}), 0);
  for (const char* copy : {"b", "c"}) {
    fs::copy(root / "a", root / copy, fs::copy_options::recursive);
    fs::remove(root / copy / "runout.csv");
  }
  {
    H5::H5File file((root / "c" / "checkpoint.h5").string(), H5F_ACC_RDWR);
    file.openGroup("/run").removeAttr("runout_first_row");
  }
  std::map<std::string, std::string> summaries;
  for (const char* folder : {"a", "b", "c"}) {
    const auto [code, text] = run_captured("run " + (root / "scene.json").string() + " --restart " +
                                           (root / folder / "checkpoint.h5").string() + " --quiet --threads 1");
    EXPECT_EQ(code, 0) << text;
    EXPECT_EQ(text.find("lacks the runout rows from t = 0") != std::string::npos, std::string(folder) == "c") << text;
    summaries[folder] = test::read_text(root / folder / "runout.json");
  }
  EXPECT_EQ(summaries["b"], summaries["a"]);
  EXPECT_NE(summaries["c"], summaries["a"]);  // measured from the front at the restart
}

// An output folder whose frames/ is a file: one line naming frames/, exit 2, nothing else written
// (the folder is prepared before the run starts, so under mpirun every rank stops alike, said once).
TEST(Crash, AnOutputFolderWhoseFramesIsAFileExitsTwoWithOneLine) {
  const test::ScratchDir dir("rel_frames_file");
  std::ofstream(dir / "s.json") << test::small_slide_json(0.05, 0.0);
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "frames") << "not a folder";
  const auto [code, out] = run_captured("run " + (dir / "s.json").string() + " --threads 1 --out " + (dir / "out").string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(out, "talus: error: cannot create output folder " + (dir / "out" / "frames").string() + ": Not a directory\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 1);  // the file alone
}

// A frames folder without write permission: VTK printed twenty lines at the first frame, after
// scene.json and energy.csv were started. Root writes there all the same, so as root the run goes
// through setpriv as the user nobody.
TEST(Crash, AnUnwritableFramesFolderExitsTwoWithOneLineBeforeAnyOutput) {
  const test::ScratchDir dir("rel_frames_locked");
  std::ofstream(dir / "s.json") << test::small_slide_json(0.05, 0.0);
  fs::create_directories(dir / "out" / "frames");
  const auto all = fs::perms::owner_all | fs::perms::group_all | fs::perms::others_all;
  fs::permissions(dir, all);
  fs::permissions(dir / "s.json", fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  fs::permissions(dir / "out", all);
  fs::permissions(dir / "out" / "frames", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                              fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const std::string as_user = ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
  const auto [code, out] = run_shell(as_user + TALUS_BINARY + " run " + (dir / "s.json").string() + " --threads 1 --out " +
                                     (dir / "out").string() + " 2>&1");
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(out, "talus: error: cannot write output folder " + (dir / "out" / "frames").string() + ": no write permission\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 1);  // frames alone
  fs::permissions(dir / "out" / "frames", fs::perms::owner_all);
}

TEST(Crash, BadSceneExitsTwoWithOneLineAndWritesNothing) {
  const test::ScratchDir dir("rel_badscene");
  std::string text = test::small_slide_json();
  const std::string courant = "\"courant\": 0.3";
  text.replace(text.find(courant), courant.size(), "\"courant\": 1e999");
  std::ofstream(dir / "bad.json") << text;
  const auto [code, out] = run_captured("run " + (dir / "bad.json").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(out.rfind("talus: error: ", 0), 0u) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_FALSE(fs::exists(dir / "out"));
  const auto [code2, out2] = run_captured("run " + ref_scene_for_missing(dir) + " --restart " + (dir / "none.h5").string() +
                                          " --out " + (dir / "out").string());
  EXPECT_EQ(code2, 2) << out2;
  EXPECT_NE(out2.find("cannot open checkpoint"), std::string::npos) << out2;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// A run never replaces its own inputs: the scene in the folder it writes to (the run writes its
// resolved scene.json there), or the work record written over the scene or over one of the run's files.
TEST(Crash, ARunThatWouldReplaceItsOwnInputsExitsTwoAndTouchesNothing) {
  const test::ScratchDir dir("rel_own_inputs");
  const std::string text = test::small_slide_json(0.02, 0.0);
  std::ofstream(dir / "scene.json") << text;
  const std::string scene = (dir / "scene.json").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"run " + scene + " --out " + dir.path().string(), "would replace the scene file"},
      {"run " + scene + " --out " + (dir / "." / "").string(), "would replace the scene file"},
      {"run " + scene + " --out " + (dir / "out").string() + " --record-work " + scene, "that is the scene file"},
      {"run " + scene + " --out " + (dir / "out").string() + " --record-work " + (dir / "out" / "energy.csv").string(),
       "the run writes its energy.csv there"},
      // (a frame's name was accepted, and the record replaced that frame of the series)
      {"run " + scene + " --out " + (dir / "out").string() + " --record-work " +
           (dir / "out" / "frames" / "particles_000001.vtu").string(),
       "the run writes its particle frames in"},
  };
  for (const auto& [args, expect] : cases) {
    const auto [code, out] = run_captured(args + " --quiet --threads 1");
    EXPECT_EQ(code, 2) << args << ": " << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_NE(out.find(expect), std::string::npos) << out;
    EXPECT_EQ(test::read_text(dir / "scene.json"), text) << args;
    EXPECT_FALSE(fs::exists(dir / "out")) << args;
    EXPECT_FALSE(fs::exists(dir / "frames")) << args;
  }
}

// An output that cannot be written is refused before the solver is built: one line, no banner
// (the folder under a file failed only once the run started; the work record after the whole run).
TEST(Crash, UnwritableOutputsAreRefusedBeforeAnyWork) {
  const test::ScratchDir dir("rel_unwritable");
  std::ofstream(dir / "s.json") << test::small_slide_json(0.02, 0.0);
  std::ofstream(dir / "a_file") << "x";
  const std::string scene = (dir / "s.json").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--out " + (dir / "a_file" / "out").string(), "is a file, not a folder"},
      {"--out " + (dir / "out").string() + " --record-work " + (dir / "none" / "r.json").string(),
       "--record-work " + (dir / "none" / "r.json").string() + ": cannot write there: the folder"},
      {"--out " + (dir / "out").string() + " --record-work " + dir.path().string(), "is a folder, not a file"},
      {"--out ''", "--out is empty"},  // an unset shell variable: it fell back to runs/<name>
      // a link to nothing: "cannot create output folder: File exists"
      {"--out " + (dir / "dangling").string(), "is a link to " + (dir / "gone").string() + ", which does not exist"},
  };
  fs::create_symlink(dir / "gone", dir / "dangling");
  for (const auto& [args, expect] : cases) {
    const auto [code, out] = run_captured("run " + scene + " " + args + " --quiet --threads 1");
    EXPECT_EQ(code, 2) << args << ": " << out;
    EXPECT_EQ(out.rfind("talus: error: ", 0), 0u) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_NE(out.find(expect), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir / "out")) << args;
  }
  // a folder where the run writes a file: the run stopped at the first write of that file, with
  // frames written and a temporary file left
  fs::create_directories(dir / "out" / "particles.pvd" / "kept");
  const auto [code, out] = run_captured("run " + scene + " --out " + (dir / "out").string() + " --quiet --threads 1");
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(out, "talus: error: output folder " + (dir / "out").string() +
                     ": particles.pvd there is a folder, where the run writes a file of that name; remove it or "
                     "choose another folder (--out)\n");
  EXPECT_FALSE(fs::exists(dir / "out" / "frames"));
  EXPECT_FALSE(fs::exists(dir / "out" / "energy.csv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "particles.pvd" / "kept"));
}

TEST(Crash, InstabilityExitsThreeWithOneLineAndTheLastGoodState) {
  const test::ScratchDir dir("rel_unstable");
  // A strong pull along x speeds the block up until it moves more than the guard allows in a step
  // (0.3 v / (c + v) of a cell, c = 36.7 m/s: past 0.08 near 13 m/s, after some 190 steps): a CFL breach.
  std::ofstream(dir / "s.json") << test::small_slide_json(
      0.5, 0.0, R"(, "gravity": [200.0, 0.0, -9.81], "guards": {"max_step_displacement": 0.08})");
  const auto [code, out] = run_captured("run " + (dir / "s.json").string() + " --quiet --threads 1 --out " + (dir / "out").string());
  EXPECT_EQ(code, 3) << out;
  const auto line = out.find("talus: error: in step ");
  ASSERT_NE(line, std::string::npos) << out;
  const std::string error = out.substr(line, out.find('\n', line) - line);  // one line holds it all
  EXPECT_NE(error.find("field displacement"), std::string::npos) << error;
  EXPECT_NE(error.find("last good state"), std::string::npos) << error;
  test::expect_readable_run_folder(dir / "out");
  EXPECT_NO_THROW(read_checkpoint((dir / "out" / "checkpoint.h5").string()));
  const nlohmann::json record = read_record(dir / "out");
  EXPECT_EQ(record.at("status"), "unstable");
  EXPECT_EQ("talus: error: " + record.at("message").get<std::string>(), error);
  EXPECT_GT(record.at("end").at("step").get<std::int64_t>(), 0);
}

// Without snapshots (guards.snapshot_interval 0) there is no last good state to write; the line said
// nothing of one, nor that the periodic checkpoint written earlier is still in the folder to resume from.
TEST(Crash, InstabilityWithoutSnapshotsNamesThePeriodicCheckpointLeft) {
  const test::ScratchDir dir("rel_unstable_no_snapshot");
  const auto error_line = [&](double checkpoint_interval, const std::string& out_name) {
    std::ofstream(dir / "s.json") << test::small_slide_json(
        0.5, checkpoint_interval,
        R"(, "gravity": [200.0, 0.0, -9.81], "guards": {"max_step_displacement": 0.08, "snapshot_interval": 0})");
    const auto [code, out] =
        run_captured("run " + (dir / "s.json").string() + " --quiet --threads 1 --out " + (dir / out_name).string());
    EXPECT_EQ(code, 3) << out;
    const auto line = out.find("talus: error: in step ");
    return line == std::string::npos ? out : out.substr(line, out.find('\n', line) - line);
  };
  const std::string with = error_line(0.02, "with");
  EXPECT_NE(with.find("| no last good state kept (guards.snapshot_interval = 0); checkpoint.h5 still holds the last "
                      "periodic checkpoint (after step "),
            std::string::npos)
      << with;
  EXPECT_NE(with.find(" s): --restart resumes from it"), std::string::npos) << with;
  const Checkpoint kept = read_checkpoint((dir / "with" / "checkpoint.h5").string());
  EXPECT_NE(with.find(fmt::format("(after step {}, ", kept.solver.step)), std::string::npos) << with;
  const std::string without = error_line(0.0, "without");
  EXPECT_NE(without.find("| no last good state kept (guards.snapshot_interval = 0)"), std::string::npos) << without;
  EXPECT_EQ(without.find("checkpoint"), std::string::npos) << without;
  EXPECT_FALSE(fs::exists(dir / "without" / "checkpoint.h5"));
}

// A frame that cannot be written mid-run (its folder replaced by a file, as a full or vanished disk
// would fail it) ends the run with talus's one line naming the frame and the system's reason, and
// nothing of VTK's own report (some twenty lines before 2026-12-06); the banner comes first in a log
// of both streams; run.json says "failed" with the same message.
TEST(Crash, AFrameThatCannotBeWrittenEndsTheRunWithOneLineAndTheRecordSaysFailed) {
  const test::ScratchDir dir("rel_frame_fails");
  std::ofstream(dir / "s.json") << test::small_slide_json(3.0, 0.0);
  const fs::path out = dir / "out", log = dir / "log.txt";
  const pid_t pid = spawn({"run", (dir / "s.json").string(), "--out", out.string(), "--quiet", "--threads", "1"}, log);
  if (!wait_for_file(out / "frames" / "particles_000002.vtu", pid, 60.0)) GTEST_SKIP() << "the run ended first";
  // (moved aside, not removed: the run may write its next frame into the folder while remove_all
  // empties it, which then fails with "Directory not empty"; a rename takes the folder away at once)
  fs::rename(out / "frames", dir / "frames_moved_aside");
  std::ofstream(out / "frames") << "not a folder";
  ASSERT_EQ(wait_for(pid), 2) << test::read_text(log);
  std::vector<std::string> lines;
  std::istringstream text(test::read_text(log));
  for (std::string line; std::getline(text, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 2u) << test::read_text(log);
  EXPECT_EQ(lines[0].rfind("talus: 1000 particles, 1 thread", 0), 0u) << lines[0];
  // (a frame written between the folder's removal and the file taking its place meets no folder at all)
  const std::regex error(
      R"(talus: error: cannot write (particle frame )?\S+/frames/particles_0000[0-9]{2}\.vtu: (Not a directory|No such file or directory))");
  EXPECT_TRUE(std::regex_match(lines[1], error)) << lines[1];
  const nlohmann::json record = read_record(out);
  EXPECT_EQ(record.at("status"), "failed");
  EXPECT_EQ("talus: error: " + record.at("message").get<std::string>(), lines[1]);
}

// Every particle leaves through the open faces: nothing is left to move, so the run ends there, as a
// run that reached its end (exit 0, the last frame empty, the energy budget closed by the outflow).
TEST(Crash, ARunWhoseParticlesAllLeaveEndsWhenTheLastOneLeaves) {
  const test::ScratchDir dir("rel_all_left");
  std::string text = test::small_slide_json(0.5, 0.0);
  const std::string top = "\"z+\": \"open\"";
  text.replace(text.find(top), top.size(), top + ", \"x+\": \"open\"");
  const std::string velocity = "\"velocity\": [2.0";
  text.replace(text.find(velocity), velocity.size(), "\"velocity\": [8.0");
  std::ofstream(dir / "s.json") << text;
  const auto [code, out] = run_captured("run " + (dir / "s.json").string() + " --threads 1 --out " + (dir / "out").string());
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("every particle had left through the open faces at t = "), std::string::npos) << out;
  EXPECT_NE(out.find("before its end time 0.5 s"), std::string::npos) << out;
  EXPECT_NE(out.find("1000 particles (8 kg, 100.00% of the mass) left through open faces"), std::string::npos) << out;
  const std::vector<fs::path> frames = test::pvd_frames(dir / "out" / "particles.pvd");
  ASSERT_GE(frames.size(), 2u);
  std::string problem;
  EXPECT_GT(test::read_frame_checked(frames.front(), &problem), 0) << problem;
  EXPECT_EQ(test::read_frame_checked(frames.back(), &problem), 0) << problem;
  EXPECT_FALSE(fs::exists(dir / "out" / "checkpoint.h5"));  // a finished run, as one that reached its end time
}

}  // namespace
}  // namespace crash_test
}  // namespace talus
