// Command-line mistakes as a user makes them: each is one line on stderr starting "talus: error: ",
// naming the option (or word) and what is allowed, exit code 2, before any work and with no output.
#include "program_fixture.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace cli_errors_test {
namespace {

namespace fs = std::filesystem;

using talus::test::ProgramResult;

class CliErrors : public talus::test::ProgramTest {
 protected:
  /// Runs `args` with the environment variable `name` set to `value` (the child inherits it).
  ProgramResult run_with_env(const char* name, const char* value, const std::string& args) const {
    ::setenv(name, value, 1);
    ProgramResult r = run(args);
    ::unsetenv(name);
    return r;
  }
};

/// Exit code 2, nothing on stdout (no work done), exactly `line` on stderr.
void expect_error_line(const ProgramResult& r, const std::string& line) {
  EXPECT_EQ(r.exit_code, 2) << line;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "talus: error: " + line + "\n");
}

// An empty value (an unset shell variable) meant "not given": --restart "" ran a fresh simulation.
// A scene read from an endless stream read without end (`talus check /dev/zero`).
TEST_F(CliErrors, AnEndlessSceneStreamIsRefused) {
  expect_error_line(run("check /dev/zero"), "/dev/zero: malformed JSON: a NUL byte at offset 0 (not a text file?)");
}

TEST_F(CliErrors, AnEmptyFileOrFolderOptionIsRefusedNamingIt) {
  expect_error_line(run("run scene.json --restart ''"),
                    "--restart is empty: give a checkpoint file, or leave --restart out for a fresh run");
  expect_error_line(run("run scene.json --record-work ''"), "--record-work is empty: give a file, or leave --record-work out");
  expect_error_line(run("bench --json ''"), "--json is empty: give a file, or leave --json out");
  expect_error_line(run("element-test spec.json --out ''"), "--out is empty: give the CSV file to write");
}

// CLI::Range lets NaN through (NaN compares false), and bench wrote it into its scene JSON, whose
// parser then failed with an internal message; text that is no number was "not in range".
TEST_F(CliErrors, BenchNumberOptionsRefuseNonFiniteValuesAndNonNumbersNamingTheRange) {
  expect_error_line(run("bench --mls linear --mls-radius nan"), "--mls-radius = nan is outside [0.5, 8]");
  expect_error_line(run("bench --mls linear --mls-radius inf"), "--mls-radius = inf is outside [0.5, 8]");
  expect_error_line(run("bench --mls linear --mls-radius -inf"), "--mls-radius = -inf is outside [0.5, 8]");
  expect_error_line(run("bench --mls-radius 9"), "--mls-radius = 9 is outside [0.5, 8]");
  expect_error_line(run("bench --threads abc"), "--threads = abc is not an integer; allowed [1, 4096]");
  // the update scene has no grid, smoother or record: their options were ignored without a word
  const std::string no_grid = ": the update scene times the constitutive update alone, with no grid, smoother or work "
                              "record, on the wall clock; leave ";
  expect_error_line(run("bench --scene update --material dp --shape bspline2"), "--shape bspline2" + no_grid + "--shape out");
  expect_error_line(run("bench --scene update --material dp --mls linear"), "--mls linear" + no_grid + "--mls out");
  expect_error_line(run("bench --scene update --material dp --mls-radius 1"), "--mls-radius 1" + no_grid + "--mls-radius out");
  expect_error_line(run("bench --scene update --material dp --record-work w.json"), "--record-work w.json" + no_grid + "--record-work out");
  expect_error_line(run("bench --scene update --material dp --stream"), "--stream" + no_grid + "--stream out");
  expect_error_line(run("bench --scene update --material dp --cpu-time"), "--cpu-time" + no_grid + "--cpu-time out");
  // without --mls the smoother's options benchmarked the step without smoothing, exit 0
  expect_error_line(run("bench --mls-variant cell"), "--mls-variant cell needs --mls linear, quadratic or cubic (smoothing is off without it)");
  expect_error_line(run("bench --mls-radius 3"), "--mls-radius 3 needs --mls linear, quadratic or cubic (smoothing is off without it)");
  expect_error_line(run("bench --mls linear --mls-reuse-strain 0.5"), "--mls-reuse-strain 0.5 needs --mls-variant reused (the particle fit does not reuse)");
  // CLI11 said "--threads: At Most 1 required but received 2"
  expect_error_line(run("bench --threads 1 --threads 2"), "--threads is given 2 times; give it once (see talus bench --help)");
  // an option that only shapes another one, given without it, was ignored without a word
  expect_error_line(run("bench --record-steps 5"), "--record-steps requires --record-work (see talus bench --help)");
  expect_error_line(run("run missing.json --record-interval 5"), "--record-interval requires --record-work (see talus run --help)");
  expect_error_line(run("bench --steps 0"), "--steps = 0 is outside [1, 1000000]");
  expect_error_line(run("bench --particles 1e6"), "--particles = 1e6 is not an integer; allowed [1000, 100000000]");
}

// talus run --stop-after: a batch job's time limit as its users write one; anything else is refused
// before the scene is read. (The forms accepted reach the scene, which is missing here.)
TEST_F(CliErrors, StopAfterTakesTheDurationsOfABatchJobAndRefusesTheRest) {
  for (const char* accepted : {"3h50m", "90m", "1.5h", "5400s", "5400", "1h2m3s", "0.5s"})
    expect_error_line(run(std::string("run missing.json --stop-after ") + accepted), "cannot open scene file missing.json: no such file");
  for (const char* refused : {"3h50", "2m3h", "1e3", "-5", "0", "0s", "nan", "inf", "h", "5 m", "1h1h"})
    expect_error_line(run(std::string("run missing.json --stop-after '") + refused + "'"),
                      std::string("--stop-after = ") + refused +
                          " is not a positive duration in h, m and s; give e.g. 3h50m, 90m, 1.5h, 5400s or 5400 (seconds)");
  // (3000000h overflowed the deadline's clock, and the run stopped at its first step with exit 75)
  expect_error_line(run("run missing.json --stop-after 8760h"), "cannot open scene file missing.json: no such file");
  for (const char* refused : {"8760h1s", "3000000h", "99999999999999999999s"})
    expect_error_line(run(std::string("run missing.json --stop-after ") + refused),
                      std::string("--stop-after = ") + refused +
                          " is longer than a year (8760h); give a shorter duration, or leave --stop-after out");
}

// The bench learned that it could not write its files only after it had run (minutes at 1e6
// particles) and printed its results.
TEST_F(CliErrors, BenchRefusesAnUnwritableOutputBeforeAnyWork) {
  const std::string bench = "bench --particles 1000 --threads 1 --steps 1 ";
  const std::string missing = (dir_ / "no_such_folder" / "b.json").string();
  expect_error_line(run(bench + "--json " + missing),
                    "--json " + missing + ": cannot write there: the folder " + (dir_ / "no_such_folder").string() +
                        " does not exist");
  expect_error_line(run(bench + "--record-work " + missing),
                    "--record-work " + missing + ": cannot write there: the folder " +
                        (dir_ / "no_such_folder").string() + " does not exist");
  expect_error_line(run(bench + "--json " + dir_.string()), "--json " + dir_.string() + ": is a folder, not a file");
  std::ofstream(dir_ / "a_file") << "x";  // a file where the folder should be: it said "does not exist"
  expect_error_line(run(bench + "--json " + (dir_ / "a_file" / "b.json").string()),
                    "--json " + (dir_ / "a_file" / "b.json").string() + ": cannot write there: " +
                        (dir_ / "a_file").string() + " is a file, not a folder");
  const std::string same = (dir_ / "b.json").string();
  expect_error_line(run(bench + "--json " + same + " --record-work " + same),
                    "--json and --record-work name the same file, " + same + ": the one would overwrite the other");
  if (::geteuid() != 0) {  // root writes into a read-only folder all the same
    const fs::path locked = dir_ / "locked";
    fs::create_directories(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
    const std::string file = (locked / "b.json").string();
    expect_error_line(run(bench + "--json " + file), "--json " + file + ": cannot write there: no write permission");
    fs::permissions(locked, fs::perms::owner_all);
  }
}

// CLI11 printed its errors in two lines without the prefix, and "talus bogus" as "A subcommand is
// required".
TEST_F(CliErrors, ParseErrorsAreOneLineWithWhereToReadMore) {
  const std::string commands = "run, check, bench, element-test, dem-springs, schema";
  expect_error_line(run("bogus"), "unknown command 'bogus'; the commands are " + commands + " (see talus --help)");
  expect_error_line(run(""), "a command is required: one of " + commands + " (see talus --help)");
  expect_error_line(run("--bogus"), "unknown option --bogus (see talus --help)");
  expect_error_line(run("run"), "scene is required (see talus run --help)");
  expect_error_line(run("bench --bogus"), "talus bench has no option --bogus (see talus bench --help)");
  // an unknown option before the scene: CLI11 listed the scene as unexpected too
  expect_error_line(run("check --restart a.h5 scene.json"), "talus check has no option --restart (see talus check --help)");
  // an option before the command: CLI11 listed its words backwards ("not expected: 2 --threads"), or
  // reported a later error ("scene is required")
  expect_error_line(run("--threads 2 run scene.json"),
                    "--threads goes after the command: talus run --threads ... (see talus run --help)");
  expect_error_line(run("--threads=2 bench"), "--threads goes after the command: talus bench --threads ... (see talus bench --help)");
  // (check takes run's --threads, to be swapped for run on a command line)
  expect_error_line(run("--threads 1 check scene.json"), "--threads goes after the command: talus check --threads ... (see talus check --help)");
  // (and run's --quiet, which check takes so that a run's line checks as it is)
  expect_error_line(run("--quiet check scene.json"), "--quiet goes after the command: talus check --quiet ... (see talus check --help)");
  expect_error_line(run("--restart a.h5 check scene.json"), "talus check has no option --restart (see talus check --help)");
  expect_error_line(run("--bogus check"), "talus check has no option --bogus (see talus check --help)");
  expect_error_line(run("dem-springs --E 1 --G 1 --nu 0 --packing hex"),
                    "--E excludes --G (see talus dem-springs --help)");
  // CLI11 said "Could not convert: --E = abc"
  expect_error_line(run("dem-springs --E abc --nu 0.2 --packing hex"), "--E = abc is not a number");
  expect_error_line(run("dem-springs --E 1e6 --nu x --packing hex"), "--nu = x is not a number");
  // element-test specs have no Markdown table: the flag was ignored and the scene table printed
  expect_error_line(run("schema --markdown --element-test"), "--markdown excludes --element-test (see talus schema --help)");
  // help and version are no errors
  for (const std::string args : {"--help", "bench --help", "--version"}) {
    const ProgramResult r = run(args);
    EXPECT_EQ(r.exit_code, 0) << args;
    EXPECT_EQ(r.err, "") << args;
    EXPECT_FALSE(r.out.empty()) << args;
  }
}

const std::string kScene = std::string(TALUS_SOURCE_DIR) + "/inputs/elastic_block_slide.json";

// The environment is input too: a bad TALUS_ISA made even --version fail, and --isa could not
// override it; OMP_NUM_THREADS = 70000 crashed in libgomp; TALUS_MEMORY_LIMIT = 1e30 overflowed to
// 0 bytes and 0.5 was truncated to 0.
TEST_F(CliErrors, EnvironmentVariablesAreCheckedAndTheOptionsOverrideThem) {
  const ProgramResult version = run_with_env("TALUS_ISA", "bogus", "--version");
  EXPECT_EQ(version.exit_code, 0) << version.err;
  // check refuses it as the run would (it said ok, and the run then stopped); its --isa overrides it
  const ProgramResult check = run_with_env("TALUS_ISA", "bogus", "check " + kScene);
  EXPECT_EQ(check.exit_code, 2) << check.err;
  EXPECT_EQ(check.err.rfind("talus: error: TALUS_ISA = 'bogus' is not a vector path this CPU and build run (unknown", 0), 0u) << check.err;
  const ProgramResult check_isa = run_with_env("TALUS_ISA", "bogus", "check " + kScene + " --isa reference");
  EXPECT_EQ(check_isa.exit_code, 0) << check_isa.err;
  const ProgramResult bad_isa = run_with_env("TALUS_ISA", "bogus", "run " + kScene + " --out " + (dir_ / "a").string());
  EXPECT_EQ(bad_isa.exit_code, 2);
  EXPECT_EQ(bad_isa.err.rfind("talus: error: TALUS_ISA = 'bogus' is not a vector path this CPU and build run (unknown", 0), 0u) << bad_isa.err;
  EXPECT_FALSE(fs::exists(dir_ / "a"));
  const ProgramResult overridden = run_with_env("TALUS_ISA", "bogus", "bench --isa reference --steps 1 --particles 1000");
  EXPECT_EQ(overridden.exit_code, 0) << overridden.err;
  // an empty --isa (an unset shell variable) ran the automatic choice without a word
  for (const char* command : {"bench", "run missing.json"})
    expect_error_line(run(std::string(command) + " --isa ''"), "--isa is empty: give auto or a vector path, or leave --isa out");
  expect_error_line(run_with_env("OMP_NUM_THREADS", "70000", "run " + kScene + " --out " + (dir_ / "b").string()),
                    "OMP_NUM_THREADS = 70000 is outside [1, 4096] (or give --threads)");
  // past an unsigned long libgomp warned and used every core: the run went on
  const ProgramResult huge = run_with_env("OMP_NUM_THREADS", "99999999999999999999", "run " + kScene + " --out " + (dir_ / "b").string());
  EXPECT_EQ(huge.exit_code, 2) << huge.err;
  EXPECT_NE(huge.err.find("talus: error: OMP_NUM_THREADS = 99999999999999999999 is outside [1, 4096] (or give --threads)\n"),
            std::string::npos) << huge.err;
  EXPECT_FALSE(fs::exists(dir_ / "b"));
  // libgomp warns of a value it cannot read and then uses every core; talus refuses it (after
  // libgomp's own line, which it prints as the program loads)
  for (const char* threads : {"0", "abc", "2.5", "4,"}) {
    const ProgramResult r = run_with_env("OMP_NUM_THREADS", threads, "run " + kScene + " --out " + (dir_ / "c").string());
    EXPECT_EQ(r.exit_code, 2) << threads;
    EXPECT_NE(r.err.find(std::string("talus: error: OMP_NUM_THREADS = '") + threads +
                         "' is not a whole number of threads in [1, 4096] (or give --threads)\n"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "c")) << threads;
  }
  const ProgramResult nested = run_with_env("OMP_NUM_THREADS", "2,1", "bench --particles 1000 --steps 1");
  EXPECT_EQ(nested.exit_code, 0) << nested.err;  // a list, one number a nesting level, is valid OpenMP
  // a bench too large for the memory stops before it allocates (1e8 particles met the OOM killer)
  const ProgramResult big = run_with_env("TALUS_MEMORY_LIMIT", "100M", "bench --particles 1000000 --steps 1");
  EXPECT_EQ(big.exit_code, 2);
  EXPECT_EQ(big.out, "");
  EXPECT_EQ(big.err.rfind("talus: error: --particles 1000000 needs about ", 0), 0u) << big.err;
  EXPECT_NE(big.err.find("but 100.0 MB is available (TALUS_MEMORY_LIMIT); use --particles "), std::string::npos) << big.err;
  const ProgramResult fits = run_with_env("TALUS_MEMORY_LIMIT", "100M", "bench --particles 100000 --steps 1 --threads 1");
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
  // so does the update scene (56 B a particle, no grid), which allocated whatever it was asked for
  const ProgramResult update =
      run_with_env("TALUS_MEMORY_LIMIT", "100M", "bench --scene update --material mu_i --particles 3000000 --steps 1");
  EXPECT_EQ(update.exit_code, 2);
  EXPECT_EQ(update.out, "");
  EXPECT_EQ(update.err, "talus: error: --particles 3000000 needs about 168.0 MB (56 B a particle) but 100.0 MB is "
                        "available (TALUS_MEMORY_LIMIT); use --particles 1607000 or fewer\n");
  // The advice: a cell size factor that makes the scene fit (particles and grid both scale with
  // 1/h^3), rounded up; fewer particles per cell only while the grid alone fits.
  for (const auto& [limit, advice] : std::vector<std::pair<const char*, std::string>>{
           {"2M", "or use fewer particles_per_cell, or run it"}, {"100K", "larger (the grid alone does not fit), or run it"}}) {
    const ProgramResult small = run_with_env("TALUS_MEMORY_LIMIT", limit, "check " + kScene);
    EXPECT_EQ(small.exit_code, 2) << small.err;
    EXPECT_NE(small.err.find(advice), std::string::npos) << small.err;
    const auto at = small.err.find("make grid.cell_size ");
    ASSERT_NE(at, std::string::npos) << small.err;
    const double factor = std::stod(small.err.substr(at + 20));
    EXPECT_GT(factor, 1.0) << small.err;
    EXPECT_LT(factor, 20.0) << small.err;  // finite and sane (it was "infx" when the grid alone did not fit)
  }
  for (const char* limit : {"1e30", "0.5", "-3G", "0x10", "inf"})  // (strtod read 0x10 as 16 bytes)
    expect_error_line(run_with_env("TALUS_MEMORY_LIMIT", limit, "check " + kScene),
                      std::string("TALUS_MEMORY_LIMIT = \"") + limit +
                          "\" is not a memory size (1 byte to 9.2e18 bytes, optionally with K, M, G or T: 8G)");
}

// A report lost to a full disk or a closed stdout ended as a success: `talus check scene > /dev/full`
// exited 0.
TEST_F(CliErrors, AReportThatCannotBeWrittenIsAnError) {
  const fs::path err = dir_ / "stderr.txt";
  const int status = std::system((std::string("\"") + TALUS_BINARY + "\" check " + kScene + " > /dev/full 2> \"" +
                                  err.string() + "\"").c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 2);
  EXPECT_EQ(talus::test::slurp(err), "talus: error: cannot write to standard output: No space left on device\n");
  // the schema is printed as it is made: the print itself fails (it read "internal error", exit 4)
  const int schema = std::system((std::string("\"") + TALUS_BINARY + "\" schema > /dev/full 2> \"" + err.string() + "\"").c_str());
  EXPECT_EQ(WIFEXITED(schema) ? WEXITSTATUS(schema) : -1, 2);
  EXPECT_EQ(talus::test::slurp(err), "talus: error: cannot write to standard output: No space left on device\n");
}

}  // namespace
}  // namespace cli_errors_test
