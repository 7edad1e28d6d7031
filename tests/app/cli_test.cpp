// The talus program as a user meets it: exit codes, one-line errors, no half-written output.
#include "../support/scratch_dir.hpp"
#include "talus/core/comm.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>
#include <sys/wait.h>

namespace cli_test {
namespace {

namespace fs = std::filesystem;
using talus::test::ScratchDir;

struct Result {
  int exit_code;
  std::string output;  // stdout and stderr together
};

Result run_shell(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
  const int status = pclose(pipe);
  return {WEXITSTATUS(status), out};
}

Result run(const std::string& args) { return run_shell(std::string(TALUS_BINARY) + " " + args + " 2>&1"); }

const std::string kInputs = std::string(TALUS_SOURCE_DIR) + "/inputs/";

TEST(Cli, HelpAndVersion) {
  const Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("run"), std::string::npos);
  EXPECT_NE(help.output.find("check"), std::string::npos);
  const Result version = run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.output.rfind("talus ", 0), 0u) << version.output;
  // CLI11 answers --version before it reads on: an extra argument went unread with exit 0
  const Result extra = run("--version extra");
  EXPECT_EQ(extra.exit_code, 2);
  EXPECT_EQ(extra.output, "talus: error: --version takes nothing else; got 'extra' (see talus --help)\n");
}

// What a first-day user looked for in --help: the exit codes and files of a run, what sets the memory
// check's limit; and `talus run --version`, which answered "scene is required".
TEST(Cli, HelpNamesExitCodesFilesAndTheMemoryLimit) {
  const Result run_help = run("run --help");
  EXPECT_EQ(run_help.exit_code, 0);
  for (const char* line : {"Exit codes:", "  75   stopped by --stop-after", "  128+N  stopped by signal N", "  3    a stability guard",
                           "run.json", "checkpoint.h5", "energy.csv", "--overwrite"})
    EXPECT_NE(run_help.output.find(line), std::string::npos) << line << "\n" << run_help.output;
  const Result check_help = run("check --help");
  EXPECT_EQ(check_help.exit_code, 0);
  EXPECT_NE(check_help.output.find("TALUS_MEMORY_LIMIT"), std::string::npos) << check_help.output;
  for (const char* args : {"run --version", "run scene.json --version", "check --version"}) {
    const Result version = run(args);
    EXPECT_EQ(version.exit_code, 2) << args;
    EXPECT_NE(version.output.find("--version belongs to talus itself"), std::string::npos) << args << ": " << version.output;
    EXPECT_NE(version.output.find("use talus --version"), std::string::npos) << version.output;
  }
}

// `talus check` takes run's --out and --threads (swap `run` for `check` on a command line): the disk
// line names that folder, and more threads than CPUs are warned about, as `talus run --threads` is.
TEST(Cli, CheckTakesRunsOutAndThreads) {
  const ScratchDir dir("cli_check_out");
  const Result checked = run("check " + kInputs + "elastic_block_slide.json --out " + (dir / "mine").string() + " --threads 4096");
  EXPECT_EQ(checked.exit_code, 0) << checked.output;
  EXPECT_NE(checked.output.find("disk       "), std::string::npos) << checked.output;
  EXPECT_NE(checked.output.find((dir / "mine").string()), std::string::npos) << checked.output;
  EXPECT_NE(checked.output.find("talus: warning: --threads 4096: 4096 threads on the"), std::string::npos) << checked.output;
  EXPECT_NE(checked.output.find("oversubscribed"), std::string::npos) << checked.output;
  EXPECT_FALSE(fs::exists(dir / "mine"));
  const Result plain = run("check " + kInputs + "elastic_block_slide.json --threads 1");
  EXPECT_EQ(plain.output.find("oversubscribed"), std::string::npos) << plain.output;
  // so too threads that OMP_NUM_THREADS asks for (they were not warned about before 2026-12-07)
  const Result env = run_shell("OMP_NUM_THREADS=4096 " + std::string(TALUS_BINARY) + " check " + kInputs +
                               "elastic_block_slide.json 2>&1");
  EXPECT_EQ(env.exit_code, 0) << env.output;
  EXPECT_NE(env.output.find("talus: warning: OMP_NUM_THREADS=4096: 4096 threads on the"), std::string::npos) << env.output;
}

// --version names the build (app/build_info.cpp): the commit of the source tree it was built from,
// the compiler, and the vector paths; the bench's JSON records the same under "build".
TEST(Cli, VersionNamesTheCommitAndTheVectorPaths) {
  const Result head = run_shell("git -C " + std::string(TALUS_SOURCE_DIR) + " rev-parse --short=12 HEAD 2>/dev/null");
  const std::string commit = head.exit_code == 0 && head.output.size() > 1
                                 ? head.output.substr(0, head.output.size() - 1)  // less the newline
                                 : std::string("unknown");
  const Result version = run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.output.find("(commit " + commit), std::string::npos) << version.output;
  EXPECT_NE(version.output.find("vector paths here: reference"), std::string::npos) << version.output;

  const ScratchDir dir("cli_version");
  const Result bench = run("bench --particles 1000 --steps 1 --json " + (dir / "bench.json").string());
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "bench.json"));
  EXPECT_EQ(j.at("build").at("commit").get<std::string>().rfind(commit, 0), 0u) << j.at("build");
  EXPECT_EQ(j.at("build").at("vector_paths").at(0), "reference");
}

// Every scene under inputs/, its folders too (terrain/, benchmarks/; element_tests/ holds the specs of
// `talus element-test`, not scenes): the top level alone was checked, and a scene shipped in terrain/
// was not.
TEST(Cli, CheckValidatesEveryShippedScene) {
  int scenes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kInputs)) {
    if (entry.path().extension() != ".json" || entry.path().parent_path().filename() == "element_tests") continue;
    const Result r = run("check " + entry.path().string());
    EXPECT_EQ(r.exit_code, 0) << entry.path() << ": " << r.output;
    EXPECT_NE(r.output.find("ok"), std::string::npos) << entry.path();
    ++scenes;
  }
  EXPECT_GE(scenes, 38);  // 2026-12-07: 12 at the top, 12 in benchmarks/, 14 in terrain/
}

TEST(Cli, BadSceneGivesOneLineExitTwoAndNoOutputFolder) {
  const ScratchDir dir("cli_bad");
  const fs::path scene = dir / "bad.json";
  std::ifstream in(kInputs + "elastic_block_slide.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("\"poisson\": 0.3"), 14, "\"poisson\": 0.7");
  std::ofstream(scene) << text;
  const fs::path out = dir / "out";
  const Result r = run("run " + scene.string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "talus: error: materials.rubber.poisson = 0.7 is outside the allowed range (-1, 0.5)\n");
  EXPECT_FALSE(fs::exists(out));
  const Result missing = run("run " + (dir / "nope.json").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("cannot open scene file"), std::string::npos);
  const Result usage = run("run");
  EXPECT_EQ(usage.exit_code, 2);
}

TEST(Cli, CheckWarnsAboutAnMlsRadiusMeasuredUnstable) {
  const ScratchDir dir("cli_mls_radius");
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(kInputs + "elastic_block_slide.json"));
  auto check_with_radius = [&](double radius) {
    scene["solver"]["smoothing"] = {{"basis", "linear"}, {"radius_factor", radius}};
    std::ofstream(dir / "scene.json") << scene.dump();
    return run("check " + (dir / "scene.json").string());
  };
  const Result wide = check_with_radius(4.0);
  EXPECT_EQ(wide.exit_code, 0) << wide.output;  // a warning, not an error
  EXPECT_NE(wide.output.find("talus: warning: solver.smoothing.radius_factor = 4 is above 2.5 cells"), std::string::npos)
      << wide.output;
  const Result usual = check_with_radius(2.0);
  EXPECT_EQ(usual.exit_code, 0) << usual.output;
  EXPECT_EQ(usual.output.find("warning"), std::string::npos) << usual.output;
}

// A body the guard leaves unsmoothed in (nearly) every pass (one particle thick, with the quadratic
// basis: A is singular at any radius) ends with a warning that smoothing had no effect, not with the
// info line of a smoothed run; a block the linear basis fits keeps the info line.
TEST(Cli, RunWarnsWhenTheMlsGuardLeftMostParticlesUnsmoothed) {
  const ScratchDir dir("cli_mls_unsmoothed");
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(kInputs + "elastic_block_slide.json"));
  scene["time"]["end"] = 0.01;
  auto run_with = [&](const std::string& basis, double top, int per_cell) {
    scene["solver"]["smoothing"] = {{"basis", basis}};
    scene["bodies"][0]["box"]["max"][2] = top;
    scene["bodies"][0]["particles_per_cell"] = per_cell;
    std::ofstream(dir / "scene.json") << scene.dump();
    return run("run " + (dir / "scene.json").string() + " --quiet --threads 2 --out " + (dir / "out").string());
  };
  const Result sheet = run_with("quadratic", 0.02, 1);  // 10 x 10 particles in one layer
  EXPECT_EQ(sheet.exit_code, 0) << sheet.output;
  EXPECT_NE(sheet.output.find("talus: warning: MLS smoothing had no effect: the guard left "), std::string::npos)
      << sheet.output;
  EXPECT_NE(sheet.output.find("particle-passes unsmoothed (100%, "), std::string::npos) << sheet.output;
  EXPECT_NE(sheet.output.find("for the quadratic basis"), std::string::npos) << sheet.output;
  EXPECT_EQ(sheet.output.find("talus: MLS smoothing:"), std::string::npos) << sheet.output;
  const Result block = run_with("linear", 0.1, 2);  // 10 x 10 x 5 cells, 2 x 2 x 2 particles each
  EXPECT_EQ(block.exit_code, 0) << block.output;
  EXPECT_NE(block.output.find("talus: MLS smoothing: "), std::string::npos) << block.output;
  EXPECT_EQ(block.output.find("had no effect"), std::string::npos) << block.output;
}

/// The elastic block slide of inputs/, ended at 0.02 s, as `dir`/short.json.
void write_short_block_slide(const fs::path& dir) {
  std::ifstream in(kInputs + "elastic_block_slide.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("\"end\": 1.0"), 10, "\"end\": 0.02");
  std::ofstream(dir / "short.json") << text;
}

TEST(Cli, RunWritesAParaViewSeries) {
  const ScratchDir dir("cli_run");
  write_short_block_slide(dir);
  const Result r = run("run " + (dir / "short.json").string() + " --out " + (dir / "out").string() + " --threads 2 --quiet");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ParaView series"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out" / "particles.pvd"));
  EXPECT_TRUE(fs::exists(dir / "out" / "energy.csv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "scene.json"));
}

// Into a file or pipe each progress line is a new line of the log: one every 30 s by default (it
// was every 2 s, 1 800 lines an hour), and the last after the last step; --progress-every sets it.
TEST(Cli, ProgressIntoALogComesEveryThirtySecondsUnlessAsked) {
  const ScratchDir dir("cli_progress");
  write_short_block_slide(dir);
  const std::string args = "run " + (dir / "short.json").string() + " --out " + (dir / "out").string() + " --threads 1";
  const auto progress_lines = [](const std::string& output) {
    std::size_t n = 0;
    for (std::size_t at = output.find("talus: step"); at != std::string::npos; at = output.find("talus: step", at + 1)) ++n;
    return n;
  };
  const Result usual = run(args);  // a run of well under 30 s
  ASSERT_EQ(usual.exit_code, 0) << usual.output;
  EXPECT_EQ(progress_lines(usual.output), 1u) << usual.output;
  EXPECT_NE(usual.output.find("  t = 0.02/0.02 s (100.0%)"), std::string::npos) << usual.output;  // the last step
  EXPECT_EQ(run(args + " --progress-every 0").output,
            "talus: error: --progress-every = 0 is outside [0.1, 86400]\n");
}

// The disk estimate (app/disk_estimate.hpp): `talus check` prints the frames' count and bound and
// the checkpoint's size (Checkpoint.SizePerParticleIsWhatTheDiskEstimateCounts), and
// `talus run` warns before it starts when they exceed the free space (here a frame every step of a
// 1 s run, a billion frames of 1.5 MB: petabytes), then runs (--stop-after ends it at once).
TEST(Cli, CheckEstimatesTheFramesDiskUseAndRunWarnsWhenTheyMayNotFit) {
  const ScratchDir dir("cli_disk");
  std::ifstream in(kInputs + "elastic_block_slide.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string check = run("check " + kInputs + "elastic_block_slide.json").output;
  EXPECT_NE(check.find("\ndisk       51 frames of at most 1.5 MB (LZ4 writes less) and a checkpoint of 1.5 MB: at most 78.0 MB; "), std::string::npos)
      << check;
  EXPECT_NE(check.find("\nok\n"), std::string::npos) << check;  // (no warning)
  // the work: particles x the steps at the initial time step (a flow that speeds up takes more: the
  // elastic block of terrain/slope_to_runout_linear.json took 7112 steps of the 6961 estimated)
  EXPECT_NE(check.find("\ntime       end 1 s, initial dt 1.551e-04 s: ~6449 steps and ~5.16e+07 particle-updates (8000 "
                       "particles x steps) at the initial time step; a flow that speeds up takes more\n"),
            std::string::npos)
      << check;
  // A frame every step: at most one a step, so the steps (about 6 448 a second at the initial time
  // step) bound the count, not the interval (10^9 a second); 10^4 s of them are 96 TB.
  const std::string interval = "\"frame_interval\": 0.02";
  ASSERT_NE(text.find(interval), std::string::npos);
  text.replace(text.find(interval), interval.size(), "\"frame_interval\": 1e-9");
  const std::string end = "\"end\": 1.0";
  ASSERT_NE(text.find(end), std::string::npos);
  text.replace(text.find(end), end.size(), "\"end\": 1e4");
  std::ofstream(dir / "many.json") << text;
  const std::string warning = "talus: warning: the outputs may not fit: about 64483284 frames (one a step: ~64483283 steps "
                              "at the initial time step, more if the flow speeds up) of at most 1.5 MB";
  const Result r = run("run " + (dir / "many.json").string() + " --out " + (dir / "out").string() +
                       " --threads 1 --quiet --stop-after 0.1s");
  EXPECT_EQ(r.exit_code, 75) << r.output;
  EXPECT_NE(r.output.find(warning), std::string::npos) << r.output;
  // `talus check` says the same (it said ok, and nothing of it), and its last line counts the warning
  const Result c = run("check " + (dir / "many.json").string());
  EXPECT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find(warning), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("\nok (1 warning above, on stderr)\n"), std::string::npos) << c.output;
}

// A run's whole command line checks as it is, `run` swapped for `check`: run's own options are taken,
// their values checked as run checks them (`talus check … --quiet` was "no option --quiet": a user's
// hunt); --restart is not (check does not check a checkpoint).
TEST(Cli, CheckTakesARunsWholeCommandLine) {
  const ScratchDir dir("cli_check_run_line");
  const std::string line = kInputs + "elastic_block_slide.json --out " + (dir / "out").string() +
                           " --threads 1 --quiet --foreground-frames --progress-every 5 --stop-after 3h50m --isa "
                           "reference --record-work " + (dir / "work.json").string() + " --record-interval 3 --overwrite";
  const Result checked = run("check " + line);
  EXPECT_EQ(checked.exit_code, 0) << checked.output;
  EXPECT_NE(checked.output.find("\nok"), std::string::npos) << checked.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "work.json"));
  const Result bad = run("check " + kInputs + "elastic_block_slide.json --stop-after 1x");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--stop-after = 1x is not a positive duration"), std::string::npos) << bad.output;
  const Result restart = run("check " + kInputs + "elastic_block_slide.json --restart a.h5");
  EXPECT_EQ(restart.exit_code, 2) << restart.output;
  // a --record-work that run would refuse (the scene file itself), check refuses too
  const Result record = run("check " + kInputs + "elastic_block_slide.json --out " + (dir / "out").string() +
                            " --record-work " + kInputs + "elastic_block_slide.json");
  EXPECT_EQ(record.exit_code, 2) << record.output;
  EXPECT_NE(record.output.find("would stop: --record-work "), std::string::npos) << record.output;
}

// check says where the runout will be measured from: the gate and the runout plane as the run resolves
// them (a default plane at a measured profile's last vertex showed only in the run's closing line)
TEST(Cli, CheckSaysWhereTheRunoutIsMeasuredFrom) {
  const Result flume = run("check " + kInputs + "denlinger_flume.json");
  EXPECT_EQ(flume.exit_code, 0) << flume.output;
  EXPECT_NE(flume.output.find("\nrunout     measured along the terrain's arc length s; gate x = 0 m (s = 0.351473 m); "
                              "runout plane from x = 1.12846 m (s = 1.66108 m)\n"),
            std::string::npos)
      << flume.output;
  const Result flat = run("check " + kInputs + "benchmarks/sand_slide_incline.json");
  EXPECT_NE(flat.output.find("\nrunout     measured along x; "), std::string::npos) << flat.output;
  EXPECT_NE(flat.output.find("no runout plane (a flat grid: give runout_plane_x for one)"), std::string::npos) << flat.output;
  const Result none = run("check " + kInputs + "elastic_block_slide.json");  // (no diagnostics.runout)
  EXPECT_EQ(none.output.find("\nrunout "), std::string::npos) << none.output;
}

// check said ok where `talus run` then stopped at once: run from its own folder, the scene.json a
// run wrote there would be replaced by the run's. Then it said ok with a note, and exited 0, and a
// script that gated on check met run's exit code 2: check now stops as run would, after its summary.
TEST(Cli, CheckNotesADefaultFolderTheRunCouldNotUse) {
  const ScratchDir dir("cli_default_folder");
  fs::create_directories(dir / "runs" / "elastic_block_slide");
  fs::copy_file(kInputs + "elastic_block_slide.json", dir / "runs" / "elastic_block_slide" / "scene.json");
  const Result inside = run_shell("cd " + dir.path().string() + " && " + TALUS_BINARY + " check runs/elastic_block_slide/scene.json 2>&1");
  EXPECT_EQ(inside.exit_code, 2) << inside.output;
  EXPECT_NE(inside.output.find("\ntalus: error: talus run without --out would stop: output folder runs/elastic_block_slide: "
                               "the run would replace the scene file runs/elastic_block_slide/scene.json"),
            std::string::npos)
      << inside.output;
  EXPECT_NE(inside.output.find("particles"), std::string::npos) << inside.output;  // (the summary comes first)
  EXPECT_EQ(inside.output.find("\nok"), std::string::npos) << inside.output;
  const Result elsewhere = run("check " + kInputs + "elastic_block_slide.json");
  EXPECT_EQ(elsewhere.exit_code, 0) << elsewhere.output;
  EXPECT_EQ(elsewhere.output.find("would stop"), std::string::npos) << elsewhere.output;
}

// run.json (app/run_record.hpp): which build ran the scene, how, on what, and how it ended, each
// field checked against what the run itself wrote or was given.
TEST(Cli, RunRecordNamesTheBuildTheCommandAndTheEnd) {
  const ScratchDir dir("cli_run_record");
  write_short_block_slide(dir);
  const fs::path out = dir / "out";
  const Result r = run("run " + (dir / "short.json").string() + " --out " + out.string() +
                       " --threads 2 --isa reference --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("run record: " + out.string() + "/run.json"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out / "run.json"));
  EXPECT_EQ(j.at("status"), "completed");
  EXPECT_EQ(j.at("message"), "");
  // the build --version names
  const Result version = run("--version");
  EXPECT_NE(version.output.find("(commit " + j.at("talus").at("commit").get<std::string>() + ","), std::string::npos)
      << version.output << j.at("talus");
  // the command and the settings it asked for
  const std::vector<std::string> command = j.at("command");
  ASSERT_EQ(command.size(), 10u);
  EXPECT_EQ(command[0], TALUS_BINARY);
  EXPECT_EQ(command[1], "run");
  EXPECT_EQ(command[2], (dir / "short.json").string());
  EXPECT_EQ(j.at("scene").at("file"), (dir / "short.json").string());
  EXPECT_EQ(j.at("scene").at("name"), "elastic_block_slide");
  EXPECT_EQ(j.at("threads"), 2);
  EXPECT_EQ(j.at("ranks"), 1);
  EXPECT_EQ(j.at("isa"), "reference");
  // the host's CPUs, and those this process may use (fewer under a binding: it recorded only these)
  const int allowed = j.at("host").at("cpus_allowed").get<int>();
  EXPECT_GE(allowed, 1);
  EXPECT_GE(j.at("host").at("logical_cpus").get<int>(), allowed);
  EXPECT_EQ(j.at("host").at("logical_cpus").get<long>(), ::sysconf(_SC_NPROCESSORS_ONLN));
  EXPECT_FALSE(j.contains("restart"));
  EXPECT_FALSE(j.contains("progress"));  // (while it ran; "end" replaces it)
  EXPECT_FALSE(fs::exists(out / ".talus.lock"));  // the folder's lock goes with the run (driver/folder_lock.hpp)
  // its end, as the other outputs have it: the last history row's step, the frames the series lists
  std::ifstream history(out / "energy.csv");
  std::string line, last;
  while (std::getline(history, line)) last = line;
  const std::string last_step = last.substr(last.find(',') + 1, last.find(',', last.find(',') + 1) - last.find(',') - 1);
  EXPECT_EQ(j.at("end").at("step").get<std::int64_t>(), std::stoll(last_step)) << last;
  EXPECT_EQ(j.at("end").at("steps_this_part"), j.at("end").at("step"));
  EXPECT_DOUBLE_EQ(j.at("end").at("time").get<double>(), 0.02);
  std::ifstream pvd(out / "particles.pvd");
  const std::string index((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  std::size_t frames = 0;
  for (std::size_t at = index.find("<DataSet"); at != std::string::npos; at = index.find("<DataSet", at + 1)) ++frames;
  EXPECT_EQ(j.at("end").at("frames_in_series").get<std::size_t>(), frames);
  EXPECT_EQ(j.at("start").at("particles"), 8000);
  EXPECT_EQ(j.at("end").at("particles"), 8000);
  EXPECT_GT(j.at("end").at("particle_updates_per_second").get<double>(), 0.0);
  EXPECT_LE(j.at("started").get<std::string>(), j.at("finished").get<std::string>());
  EXPECT_EQ(j.at("started").get<std::string>().size(), 20u) << j.at("started");  // 2026-12-06T13:40:05Z
  // The resolved scene beside it stays a scene: the record is not in it.
  EXPECT_EQ(run("check " + (out / "scene.json").string()).exit_code, 0);
  // A fresh run in the same folder replaces the record.
  const Result again = run("run " + (dir / "short.json").string() + " --out " + out.string() + " --threads 1 --quiet");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(out / "run.json")).at("threads"), 1);
  // The budget's gap: a share of the energy available, and both in joules.
  const nlohmann::json& end = j.at("end");
  EXPECT_GT(end.at("energy_available_joules").get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(end.at("energy_budget_gap").get<double>(),
                   end.at("energy_budget_gap_joules").get<double>() / end.at("energy_available_joules").get<double>());
  // A run that time.max_steps ends before time.end says so (it was "completed" with no word).
  nlohmann::json capped = nlohmann::json::parse(std::ifstream(dir / "short.json"));
  capped["time"]["max_steps"] = 3;
  std::ofstream(dir / "capped.json") << capped.dump();
  const Result short_run = run("run " + (dir / "capped.json").string() + " --out " + (dir / "capped").string() +
                               " --threads 1 --quiet");
  ASSERT_EQ(short_run.exit_code, 0) << short_run.output;
  EXPECT_NE(short_run.output.find("talus: stopped at time.max_steps = 3, before its end time 0.02 s"), std::string::npos)
      << short_run.output;
  const nlohmann::json c = nlohmann::json::parse(std::ifstream(dir / "capped" / "run.json"));
  EXPECT_EQ(c.at("status"), "completed");
  EXPECT_EQ(c.at("message").get<std::string>().rfind("stopped at time.max_steps = 3, at t = ", 0), 0u) << c.at("message");
}

TEST(Cli, BenchWritesTheJsonContract) {
  const ScratchDir dir("cli_bench");
  const fs::path json = dir / "bench.json";
  const Result r = run("bench --scene block --particles 2000 --shape linear --material elastic --mls off --threads 1 --steps 2 --json " +
                       json.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* key : {"\"particle_updates_per_second\"", "\"phases\"", "\"bytes_per_particle\"", "\"particles\"", "\"steps\": 2",
                          "\"threads\": 1", "\"p2g\"", "\"g2p\""})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  // a serial bench is one rank: nothing exchanged, its phases are the largest and the mean alike
  const nlohmann::json serial = nlohmann::json::parse(text);
  EXPECT_EQ(serial["ranks"], 1);
  EXPECT_EQ(serial["exchange_bytes_per_step"].get<double>(), 0.0);
  EXPECT_EQ(serial["imbalance"].get<double>(), 1.0);
  double phase_sum = 0.0;
  for (const auto& [phase, seconds] : serial["phases"].items()) {
    EXPECT_EQ(serial["phases_max"][phase], seconds) << phase;
    EXPECT_EQ(serial["phases_mean"][phase], seconds) << phase;
    phase_sum += seconds.get<double>();
  }
  // "other" (outside the phases) is there as the text prints it, so the phases add up to the wall
  EXPECT_TRUE(serial["phases"].contains("other")) << text;
  ASSERT_EQ(serial["rank_phases"].size(), 1u) << text;  // the key a 1..N-rank script reads, as on N ranks
  EXPECT_EQ(serial["rank_phases"][0]["wall"], serial["wall_seconds"]);
  EXPECT_NEAR(phase_sum, serial["wall_seconds"].get<double>(), 1e-9 * serial["wall_seconds"].get<double>());
  // the update scene names its rate with the key every bench JSON has
  const fs::path update_json = dir / "update.json";
  const Result update = run("bench --scene update --material dp --particles 2000 --threads 1 --steps 2 --json " + update_json.string());
  EXPECT_EQ(update.exit_code, 0) << update.output;
  const nlohmann::json u = nlohmann::json::parse(std::ifstream(update_json));
  EXPECT_EQ(u["scene"], "update");
  EXPECT_GT(u["particle_updates_per_second"].get<double>(), 0.0) << u.dump();
  EXPECT_EQ(r.output.find("ranks"), std::string::npos) << r.output;  // the text is as before MPI
  // the granular column with Drucker-Prager, every shape function
  for (const char* shape : {"linear", "ugimp", "cpgimp", "bspline2"}) {
    const Result column = run(std::string("bench --scene column --particles 2000 --material dp --threads 1 --steps 2 --shape ") + shape);
    EXPECT_EQ(column.exit_code, 0) << column.output;
    EXPECT_NE(column.output.find("column scene"), std::string::npos) << column.output;
  }
  // The shear scene keeps (nearly) every particle on the yield surface: the share the bench reports
  // for the last step, read from its JSON.
  const fs::path shear_json = dir / "bench_shear.json";
  const Result shear = run("bench --scene shear --particles 4000 --material dp --shape bspline2 --threads 1 --steps 3 --json " +
                           shear_json.string());
  EXPECT_EQ(shear.exit_code, 0) << shear.output;
  std::ifstream shear_in(shear_json);
  const nlohmann::json shear_result = nlohmann::json::parse(shear_in);
  ASSERT_TRUE(shear_result.contains("plastic_share_last_step")) << shear.output;
  EXPECT_GT(shear_result["plastic_share_last_step"].get<double>(), 0.8) << shear.output;
  const Result shear_elastic = run("bench --scene shear --material elastic");
  EXPECT_EQ(shear_elastic.exit_code, 2);
  EXPECT_NE(shear_elastic.output.find("--scene shear needs --material dp"), std::string::npos) << shear_elastic.output;
  // --mls runs the smoother and reports its phase.
  const fs::path mls_json = dir / "bench_mls.json";
  const Result mls = run("bench --particles 2000 --mls quadratic --threads 1 --steps 2 --json " + mls_json.string());
  EXPECT_EQ(mls.exit_code, 0) << mls.output;
  EXPECT_NE(mls.output.find("MLS quadratic"), std::string::npos) << mls.output;
  std::ifstream mls_in(mls_json);
  const std::string mls_text((std::istreambuf_iterator<char>(mls_in)), std::istreambuf_iterator<char>());
  for (const char* key : {"\"smooth\"", "\"mls\": \"quadratic\"", "\"mls_terms\": 10"})
    EXPECT_NE(mls_text.find(key), std::string::npos) << key;
  const Result bad_mls = run("bench --mls quartic");
  EXPECT_EQ(bad_mls.exit_code, 2);
  EXPECT_NE(bad_mls.output.find("--mls quartic: unknown; available: off, linear, quadratic, cubic"), std::string::npos);
  const Result refused = run("bench --shape quintic");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.output.find("--shape quintic"), std::string::npos);
}


// `talus bench` under mpirun (docs/performance.md "Distributed runs (MPI)"): rank 0 alone prints
// and writes, the rate counts every rank's particles, the phases are the largest and the mean over
// the ranks, and the slabs' exchange is reported. Skipped without MPI or mpirun.
// Under OMP_WAIT_POLICY=PASSIVE every parallel region wakes sleeping threads (about 100 us a region
// at 16 threads on the 2026-12-04 node): a bench on several threads says so, and its JSON records
// the policy; on one thread, or with another policy, it says nothing.
TEST(Cli, BenchNotesAPassiveWaitPolicy) {
  const char* inherited = std::getenv("OMP_WAIT_POLICY");
  const std::string saved = inherited ? inherited : "";
  const ScratchDir dir("cli_wait_policy");
  const fs::path json = dir / "bench.json";
  ::setenv("OMP_WAIT_POLICY", "passive", 1);
  const Result passive = run("bench --particles 2000 --threads 2 --steps 1 --json " + json.string());
  const Result one_thread = run("bench --particles 2000 --threads 1 --steps 1");
  ::setenv("OMP_WAIT_POLICY", "active", 1);
  const Result active = run("bench --particles 2000 --threads 2 --steps 1");
  if (inherited) ::setenv("OMP_WAIT_POLICY", saved.c_str(), 1); else ::unsetenv("OMP_WAIT_POLICY");
  const std::string note = "note: OMP_WAIT_POLICY=PASSIVE";
  ASSERT_EQ(passive.exit_code, 0) << passive.output;
  EXPECT_NE(passive.output.find(note), std::string::npos) << passive.output;
  EXPECT_EQ(one_thread.output.find(note), std::string::npos) << one_thread.output;
  EXPECT_EQ(active.output.find(note), std::string::npos) << active.output;
  std::ifstream in(json);
  EXPECT_EQ(nlohmann::json::parse(in)["omp_wait_policy"], "passive");
}

TEST(Cli, BenchUnderMpirunReportsAllRanks) {
  if (!talus::mpi_built() || std::system("command -v mpirun > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "no MPI build or no mpirun";
  const ScratchDir dir("cli_bench_mpi");
  // (root in a container: Open MPI may run as root, and copies through /dev/shm without cross-memory attach)
  const std::string mpirun = "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
                             "OMPI_MCA_btl_vader_single_copy_mechanism=none "
                             "mpirun -np 2 " + std::string(TALUS_BINARY) + " ";
  auto run_mpi = [&](const std::string& args) {
    FILE* pipe = popen((mpirun + args + " 2>&1").c_str(), "r");
    std::string out;
    std::array<char, 4096> buffer;
    while (fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
    const int status = pclose(pipe);
    return Result{WEXITSTATUS(status), out};
  };
  const std::string args = "bench --scene shear --material dp --particles 4000 --threads 1 --steps 2 --json ";
  const Result one = run(args + (dir / "one.json").string());
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const Result two = run_mpi(args + (dir / "two.json").string());
  ASSERT_EQ(two.exit_code, 0) << two.output;
  std::size_t headers = 0;
  for (std::size_t at = two.output.find("talus bench:"); at != std::string::npos; at = two.output.find("talus bench:", at + 1))
    ++headers;
  EXPECT_EQ(headers, 1u) << two.output;
  EXPECT_NE(two.output.find("2 ranks x 1 thread"), std::string::npos) << two.output;
  EXPECT_NE(two.output.find("kB of node sums exchanged a step"), std::string::npos) << two.output;
  std::ifstream one_in(dir / "one.json"), two_in(dir / "two.json");
  const nlohmann::json a = nlohmann::json::parse(one_in), b = nlohmann::json::parse(two_in);
  EXPECT_EQ(b["ranks"], 2);
  EXPECT_EQ(b["particles"], a["particles"]);  // all ranks' particles, not rank 0's
  EXPECT_GT(b["exchange_bytes_per_step"].get<double>(), 0.0);
  EXPECT_GE(b["imbalance"].get<double>(), 1.0);
  EXPECT_GT(b["shared_tiles"].get<int>(), 0);
  for (const auto& [phase, seconds] : b["phases_max"].items()) {
    EXPECT_GE(seconds.get<double>(), b["phases_mean"][phase].get<double>()) << phase;
    EXPECT_EQ(b["phases"][phase], seconds) << phase;
  }
  // the shear scene's stress from the body's extent over both slabs: nearly every particle plastic
  ASSERT_TRUE(b.contains("plastic_share_last_step")) << two.output;
  EXPECT_GT(b["plastic_share_last_step"].get<double>(), 0.8) << two.output;
  // a mode that cannot be split is refused once, with exit code 2 on every rank
  const Result update = run_mpi("bench --scene update --material dp --particles 2000");
  EXPECT_EQ(update.exit_code, 2) << update.output;
  const std::string refusal = "--scene update: one rank only";
  const std::size_t first = update.output.find(refusal);
  EXPECT_NE(first, std::string::npos) << update.output;
  EXPECT_EQ(update.output.find(refusal, first + 1), std::string::npos) << update.output;
}


// The work recorder (docs/performance.md "Scaling"): the bench records its extra steps, every
// colour pass lists each block once, and a run records every --record-interval-th step with the
// run loop's own time.
TEST(Cli, BenchAndRunRecordTheWorkDistribution) {
  const ScratchDir dir("cli_record");
  const fs::path bench_record = dir / "bench_record.json";
  const Result b = run("bench --particles 2000 --threads 1 --steps 1 --record-steps 2 --record-work " + bench_record.string());
  ASSERT_EQ(b.exit_code, 0) << b.output;
  std::ifstream bin(bench_record);
  const nlohmann::json rb = nlohmann::json::parse(bin);
  EXPECT_EQ(rb["format"], "talus-work-record/1");
  ASSERT_EQ(rb["steps"].size(), 2u);
  EXPECT_GE(rb["fork_join_seconds"].size(), 2u);
  EXPECT_EQ(rb["barrier_seconds"].size(), rb["fork_join_seconds"].size());
  // the OpenMP settings those costs depend on travel with them (PASSIVE: threads woken per region)
  const char* wait_policy = std::getenv("OMP_WAIT_POLICY");
  EXPECT_EQ(rb["omp_wait_policy"], wait_policy ? wait_policy : "unset");
  for (const auto& step : rb["steps"]) {
    std::size_t p2g_particles = 0, stress_particles = 0, passes = 0;
    double listed = 0.0;
    for (const auto& region : step["regions"]) {
      listed += region["seconds"].get<double>();
      if (region["schedule"] != "dynamic") continue;
      EXPECT_EQ(region["block_seconds"].size(), region["block_particles"].size());
      std::size_t sum = 0;
      for (const auto& n : region["block_particles"]) sum += n.get<std::size_t>();
      const std::string name = region["name"];
      if (name.rfind("p2g colour", 0) == 0) {
        p2g_particles += sum;
        // the 8 colours share one parallel region: a fork/join for the first, a barrier for the others
        EXPECT_EQ(region["parallel_regions"], passes == 0 ? 1 : 0) << name;
        EXPECT_EQ(region.value("barriers", 0), passes == 0 ? 0 : 1) << name;
        ++passes;
      }
      if (name == "stress") stress_particles = sum;
    }
    // the node work between two scatters is one parallel region (TileStages); the bench's block has
    // slip walls, whose ghosts are folded and mirrored in the node phase's loop, and a frictional
    // floor: the ghosts below it next to the walls are folded into the nodes below the floor like
    // any other, so no mirror waits for a barrier (grid_update.hpp)
    int grid_regions = 0;
    for (const auto& region : step["regions"]) {
      const std::string name = region["name"];
      if (name != "grid update" && name != "remap grid") continue;
      ++grid_regions;
      EXPECT_EQ(region["parallel_regions"], 1) << name;
      EXPECT_EQ(region.value("barriers", 0), 0) << name;
    }
    EXPECT_EQ(grid_regions, 2);
    EXPECT_EQ(passes, 8u);
    EXPECT_EQ(p2g_particles, step["particles"].get<std::size_t>());
    EXPECT_EQ(stress_particles, step["particles"].get<std::size_t>());
    // the recorder's own bookkeeping is timed between the regions: a part of the step, none of a region
    const double own = step["recorder_seconds"].get<double>();
    EXPECT_GT(own, 0.0);
    EXPECT_LE(listed + own, step["seconds"].get<double>() * 1.000001);
  }
  // MLS: the strain pass and the fit are loops over work units like the stress pass (the fit's
  // units are columns of cells): every particle in one unit, each unit with its time
  const fs::path mls_record = dir / "mls_record.json";
  const Result m = run("bench --particles 2000 --threads 1 --steps 1 --record-steps 1 --mls linear --mls-radius 1 "
                       "--record-work " + mls_record.string());
  ASSERT_EQ(m.exit_code, 0) << m.output;
  std::ifstream min(mls_record);
  const nlohmann::json rm = nlohmann::json::parse(min);
  int smooth_loops = 0, strain_loops = 0;
  for (const auto& region : rm["steps"][0]["regions"]) {
    if (region["name"] != "mls smooth" && region["name"] != "mls strain") continue;
    ++(region["name"] == "mls smooth" ? smooth_loops : strain_loops);
    EXPECT_EQ(region["schedule"], "dynamic");
    EXPECT_EQ(region["parallel_regions"], 1);
    ASSERT_EQ(region["block_seconds"].size(), region["block_particles"].size());
    std::size_t sum = 0;
    double block_total = 0.0;
    for (const auto& n : region["block_particles"]) sum += n.get<std::size_t>();
    for (const auto& t : region["block_seconds"]) block_total += t.get<double>();
    EXPECT_EQ(sum, rm["steps"][0]["particles"].get<std::size_t>());
    EXPECT_GT(block_total, 0.0);
    EXPECT_LE(block_total, region["seconds"].get<double>() * 1.000001);  // one thread: the units within the loop
  }
  EXPECT_EQ(smooth_loops, 1);
  EXPECT_EQ(strain_loops, 1);
  std::ifstream in(kInputs + "elastic_block_slide.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("\"end\": 1.0"), 10, "\"end\": 0.02");
  std::ofstream(dir / "short.json") << text;
  const fs::path run_record = dir / "run_record.json";
  const Result r = run("run " + (dir / "short.json").string() + " --out " + (dir / "out").string() +
                       " --threads 1 --quiet --record-interval 3 --record-work " + run_record.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream rin(run_record);
  const nlohmann::json rr = nlohmann::json::parse(rin);
  const auto steps = rr["run_steps"].get<std::size_t>();
  EXPECT_EQ(rr["steps"].size(), (steps + 2) / 3);
  EXPECT_EQ(rr["steps"][1]["step"], 3);
  EXPECT_EQ(rr["record_interval"], 3);  // too short a run to be thinned (tests/solver/work_recorder_test.cpp)
  EXPECT_EQ(rr["steps"][0]["regions"].back()["name"], "output and guards");
  EXPECT_EQ(rr["omp_wait_policy"], wait_policy ? wait_policy : "unset");
  EXPECT_GE(rr["fork_join_seconds"].size(), 2u);
  EXPECT_GT(rr["run_background_seconds"].get<double>(), 0.0);  // the frames, written on their own thread
  // the history rows, timed apart as a parallel part of the loop (at least the last row: the energies' sum)
  EXPECT_GT(rr["run_history_seconds"].get<double>(), 0.0);
  EXPECT_LT(rr["run_history_seconds"].get<double>() + rr["run_snapshot_seconds"].get<double>(),
            rr["run_other_seconds"].get<double>());
  EXPECT_GE(rr["run_history_regions"].get<std::int64_t>(), 1);
  // Frames in the foreground are the run loop's own time: nothing in the background.
  const Result f = run("run " + (dir / "short.json").string() + " --out " + (dir / "out").string() +
                       " --threads 1 --quiet --foreground-frames --record-work " + run_record.string());
  ASSERT_EQ(f.exit_code, 0) << f.output;
  std::ifstream fin(run_record);
  EXPECT_EQ(nlohmann::json::parse(fin)["run_background_seconds"].get<double>(), 0.0);
}

// A scene with runout diagnostics ends with the runout distance and where its files are (issue 7).
TEST(Cli, RunWithRunoutDiagnosticsPrintsTheRunoutAndItsFiles) {
  const ScratchDir scratch("cli_runout");
  const fs::path dir = scratch / "out";  // the run makes its folder
  const Result r = run("run " + kInputs + "benchmarks/sand_slide_incline.json --quiet --threads 2 --out " + dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("talus: runout: front at s = "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("beyond the gate (diagnostics.runout.gate_x, s = 0.6102 m)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ParaView series: " + (dir / "particles.pvd").string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir / "runout.json").string()), std::string::npos) << r.output;
  for (const char* f : {"runout.csv", "runout.json", "deposit.csv", "particles.pvd"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "terrain.vtu"));  // a flat grid has no terrain surface
}

// An open bed on a terrain grid: check and run warn before the start, and the runout's closing lines
// say that the mass left through faces other than x+ (runout.json had outflow_mass_share 1 and
// limited_by_outflow false, and the lines printed a front of a remnant as the runout).
TEST(Cli, ASlideThroughAnOpenBedIsWarnedAboutBeforeAndAfterTheRun) {
  const ScratchDir dir("cli_open_bed");
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(kInputs + "terrain/incline30_coarse.json"));
  scene["boundaries"]["z-"] = "open";
  scene["time"]["end"] = 1.0;  // (every particle has left by about 0.45 s: the fall of the block's 1 m)
  scene["diagnostics"] = {{"runout", nlohmann::json::object()}};
  std::ofstream(dir / "scene.json") << scene.dump();
  const std::string before = "talus: warning: boundaries.z- = \"open\" on a terrain grid";
  const Result check = run("check " + (dir / "scene.json").string());
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find(before), std::string::npos) << check.output;
  const Result r = run("run " + (dir / "scene.json").string() + " --quiet --threads 2 --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(before), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("talus: warning: runout: 100.00% of the mass left through open faces other than x+ (open: "
                          "x-, z-, z+; 100.00% left in all): the front and tail are those of the last sample with "
                          "particles in the grid, not of the flow; z- is the bed of this terrain grid, so the material "
                          "fell through the ground"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("front and tail of the mass still in the grid"), std::string::npos) << r.output;
  const nlohmann::json result = nlohmann::json::parse(std::ifstream(dir / "out" / "runout.json"));
  EXPECT_EQ(result.at("outflow_mass_share").get<double>(), 1.0);
  EXPECT_FALSE(result.at("limited_by_outflow").get<bool>());
  // run.json says through which face it left (it gave only the count in all): each open face's
  // particles and mass, the bed's z- nearly all of it
  const nlohmann::json record = nlohmann::json::parse(std::ifstream(dir / "out" / "run.json"));
  const nlohmann::json& by_face = record.at("end").at("outflow_by_face");
  EXPECT_EQ(by_face.size(), 4u) << by_face;  // x-, x+, z-, z+: the open faces, and no other
  std::int64_t particles = 0;
  for (const char* face : {"x-", "x+", "z-", "z+"}) particles += by_face.at(face).at("particles").get<std::int64_t>();
  EXPECT_EQ(particles, record.at("end").at("outflow_particles").get<std::int64_t>());
  EXPECT_GT(by_face.at("z-").at("particles").get<std::int64_t>(), particles / 2) << by_face;
  EXPECT_GT(by_face.at("z-").at("mass_kg").get<double>(), 0.0);
  // and names the bodies whose indices the frames' `body` array holds
  EXPECT_EQ(record.at("body_names"), nlohmann::json::array({"block"}));
}

TEST(Cli, RunOnManyThreadsSuggestsBlockBuffersForFewBlocksPerColourPass) {
  // the default flume at the start: 10 blocks a colour pass on average; 8 threads would want 16 or more
  const ScratchDir dir("cli_scatter_hint");
  for (const char* name : {"denlinger_flume", "denlinger_flume_block_buffers"}) {
    std::ifstream in(kInputs + name + ".json");
    nlohmann::json scene = nlohmann::json::parse(in);
    scene["time"]["end"] = 0.0005;
    scene["output"]["frame_interval"] = 0.0005;
    std::ofstream(dir / (std::string(name) + ".json")) << scene.dump();
  }
  auto run_flume = [&](const std::string& name, int threads) {
    return run("run " + (dir / (name + ".json")).string() + " --quiet --threads " + std::to_string(threads) +
               " --out " + (dir / "out").string());
  };
  const std::string note = "blocks per colour pass on 8 threads";
  const Result many = run_flume("denlinger_flume", 8);
  ASSERT_EQ(many.exit_code, 0) << many.output;
  EXPECT_NE(many.output.find(note), std::string::npos) << many.output;
  EXPECT_NE(many.output.find("solver.scatter = \"block_buffers\""), std::string::npos) << many.output;
  const Result few = run_flume("denlinger_flume", 2);
  ASSERT_EQ(few.exit_code, 0) << few.output;
  EXPECT_EQ(few.output.find("blocks per colour pass"), std::string::npos) << few.output;
  const Result buffers = run_flume("denlinger_flume_block_buffers", 8);
  ASSERT_EQ(buffers.exit_code, 0) << buffers.output;
  EXPECT_EQ(buffers.output.find("blocks per colour pass"), std::string::npos) << buffers.output;
}

}  // namespace
}  // namespace cli_test
