// The talus command-line program: parses the subcommand and reports errors in one line.
#include "commands.hpp"
#include "talus/core/comm.hpp"
#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/core/version.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <exception>
#include <string>

namespace {

/// A CLI11 parse error as talus prints every error: one line after "talus: error: ", with where to read
/// more. CLI11's own print is two lines without the prefix, and for a word that is no command it
/// says only that a subcommand is required.
std::string parse_error_line(CLI::App& app, const CLI::ParseError& e) {
  const std::vector<CLI::App*> given = app.get_subcommands();  // require_subcommand(1): at most one
  if (!given.empty()) return fmt::format("{} (see talus {} --help)", e.what(), given.front()->get_name());
  std::string commands;
  for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; }))
    commands += (commands.empty() ? "" : ", ") + command->get_name();
  const std::vector<std::string> words = app.remaining();
  std::string what = e.what();
  if (words.empty()) what = "a command is required: one of " + commands;
  else if (words.front().rfind('-', 0) == 0) what = fmt::format("unknown option {}", words.front());
  else what = fmt::format("unknown command '{}'; the commands are {}", words.front(), commands);
  return what + " (see talus --help)";
}

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun (and with an MPI build) every rank runs this same program; otherwise nothing changes.
  talus::MpiSession mpi(argc, argv);
  const talus::Comm world = talus::Comm::world();
  CLI::App app{
      "talus: explicit 3D material point method (MPM) solver for granular runout.\n"
      "Scene files are JSON (SI units); see docs/scene-reference.md."};
  app.set_version_flag("--version", std::string("talus ") + talus::kVersion);
  app.require_subcommand(1);
  talus::app::add_run_command(app);
  talus::app::add_check_command(app);
  talus::app::add_bench_command(app);
  talus::app::add_element_test_command(app);
  talus::app::add_dem_springs_command(app);
  talus::app::add_schema_command(app);

  try {
    app.parse(argc, argv);  // the commands that run kernels choose their path (select_isa_option)
    return talus::app::exit_code();
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (world.root()) fmt::print(stderr, "talus: error: {}\n", talus::Error::one_line(parse_error_line(app, e)));
    return 2;
  } catch (const talus::Error& e) {
    // Errors that reach here are those every rank meets alike (the scene, the options): rank 0
    // reports them once and every rank exits with the same code. A rank that fails alone during a
    // run ends the job itself (run_command.cpp).
    if (world.root()) fmt::print(stderr, "talus: error: {}\n", e.what());
    return e.exit_code();
  } catch (const std::exception& e) {
    fmt::print(stderr, "talus: internal error: {}\n", e.what());
    return 4;
  }
  return 0;
}

namespace talus::app {

int& exit_code() {
  static int code = 0;
  return code;
}

void add_isa_option(CLI::App* command, const std::shared_ptr<std::string>& value) {
  command->add_option("--isa", *value,
                      "Vector path of the kernels: auto (the best this CPU has) or one of " + [] {
                        std::string names;
                        for (const std::string& n : available_isas()) names += (names.empty() ? "" : ", ") + n;
                        return names;
                      }() + " (reference: the plain C++ path). Every path gives the same bits; also TALUS_ISA");
}

void set_threads(int threads) {
  if (threads > 0) {
    omp_set_num_threads(threads);
    return;
  }
  // OMP_NUM_THREADS=70000 crashed in the first parallel region (libgomp could not make the threads):
  // hold the environment to the range --threads has.
  const int from_environment = omp_get_max_threads();
  if (from_environment > 4096)
    throw input_error(fmt::format("OMP_NUM_THREADS = {} is outside [1, 4096] (or give --threads)", from_environment));
}

void select_isa_option(const std::string& value) {
  // --isa, else TALUS_ISA. Read here, by the commands that run kernels, and not before parsing: a bad
  // TALUS_ISA made even --help and --version fail, and --isa could not override it.
  if (!value.empty())
    select_isa(value);
  else
    select_isa_from_environment();
}

}  // namespace talus::app
