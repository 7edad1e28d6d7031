// The talus command-line program: parses the subcommand and reports errors in one line.
#include "build_info.hpp"
#include "commands.hpp"
#include "option_checks.hpp"
#include "talus/core/comm.hpp"
#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <system_error>

namespace {

/// A CLI11 parse error as talus prints every error: one line after "talus: error: ", with where to read
/// more. CLI11's own print is two lines without the prefix, and for a word that is no command it
/// says only that a subcommand is required.
std::string parse_error_line(CLI::App& app, const CLI::ParseError& e) {
  const std::vector<CLI::App*> given = app.get_subcommands();  // require_subcommand(1): at most one
  if (!given.empty()) {
    const std::string name = given.front()->get_name();
    // (`talus run --version` said "scene is required"; `talus run s.json --version`, "has no option")
    const std::vector<std::string>& words = talus::app::command_line();
    if (words.size() > 1 && std::find(words.begin() + 1, words.end(), "--version") != words.end() &&
        !given.front()->get_option_no_throw("--version"))
      return fmt::format("--version belongs to talus itself, not to talus {}: use talus --version", name);
    // An option before the command (`talus --threads 2 run scene.json`): CLI11 left it to the
    // program and listed its words backwards ("not expected: 2 --threads"), or reported a later
    // error (`talus --bogus check` said "scene is required"). Every option belongs to a command.
    for (const std::string& word : app.remaining())
      if (word.rfind('-', 0) == 0 && word.size() > 1) {
        const std::string option = word.substr(0, word.find('='));
        bool known = false;
        try {
          known = given.front()->get_option_no_throw(option) != nullptr;
        } catch (const CLI::Error&) {  // (a word CLI11 cannot take for an option name)
        }
        return known ? fmt::format("{} goes after the command: talus {} {} ... (see talus {} --help)", option, name,
                                   option, name)
                     : fmt::format("talus {} has no option {} (see talus {} --help)", name, option, name);
      }
    // CLI11 lists every word it could not place ("not expected: scene.json --threads"), the scene
    // file among them when an unknown option swallowed its place: name the unknown option first.
    if (dynamic_cast<const CLI::ExtrasError*>(&e))
      for (const std::string& word : given.front()->remaining())
        if (word.rfind('-', 0) == 0 && word.size() > 1)
          return fmt::format("talus {} has no option {} (see talus {} --help)", name, word, name);
    // an option given twice: CLI11 says "--threads: At Most 1 required but received 2"
    const std::string what = e.what();
    const std::string twice = ": At Most 1 required but received ";
    if (const auto at = what.find(twice); dynamic_cast<const CLI::ArgumentMismatch*>(&e) && at != std::string::npos)
      return fmt::format("{} is given {} times; give it once (see talus {} --help)", what.substr(0, at),
                         what.substr(at + twice.size()), name);
    return fmt::format("{} (see talus {} --help)", what, name);
  }
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

/// A report that could not reach stdout (a full disk, a closed pipe): one line, exit 2.
int stdout_failed(int error) {
  fmt::print(stderr, "talus: error: cannot write to standard output: {}\n", std::strerror(error));
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun (and with an MPI build) every rank runs this same program; otherwise nothing changes.
  talus::MpiSession mpi(argc, argv);
  talus::app::command_line().assign(argv, argv + argc);
  const talus::Comm world = talus::Comm::world();
  CLI::App app{
      "talus: explicit 3D material point method (MPM) solver for granular runout.\n"
      "Scene files are JSON (SI units); see docs/scene-reference.md."};
  app.set_version_flag("--version", talus::app::build_summary());
  app.require_subcommand(1);
  talus::app::add_run_command(app);
  talus::app::add_check_command(app);
  talus::app::add_bench_command(app);
  talus::app::add_element_test_command(app);
  talus::app::add_dem_springs_command(app);
  talus::app::add_schema_command(app);

  // Under mpirun, the commands that do not use the ranks (schema, element-test, dem-springs,
  // --version, --help) run on rank 0 alone: on every rank they printed their output once per rank
  // (`mpirun talus schema > s.json` interleaved two copies) and wrote their files twice.
  if (world.distributed() && !world.root()) {
    const auto command = std::find_if(argv + 1, argv + argc, [](const char* a) { return a[0] != '-'; });
    const std::string word = command == argv + argc ? "" : *command;
    if (word != "run" && word != "check" && word != "bench") return 0;
  }
  try {
    app.parse(argc, argv);  // the commands that run kernels choose their path (select_isa_option)
    // What a command printed may still sit in stdout's buffer: a full disk or a closed pipe must
    // not end as a success (`talus check scene > /dev/full` exited 0 with its report lost)
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) return stdout_failed(errno);
    return talus::app::exit_code();
  } catch (const CLI::CallForVersion& e) {
    // CLI11 answers --version as soon as it meets it: `talus --version extra` printed the version and
    // exited 0 with "extra" unread
    if (argc > 2) {
      std::string rest;  // every argument but the --version answered
      bool skipped = false;
      for (int i = 1; i < argc; ++i) {
        if (!skipped && std::string(argv[i]) == "--version") {
          skipped = true;
          continue;
        }
        rest += (rest.empty() ? "" : " ") + std::string(argv[i]);
      }
      if (world.root())
        fmt::print(stderr, "talus: error: {}\n",
                   talus::Error::one_line(fmt::format("--version takes nothing else; got '{}' (see talus --help)", rest)));
      return 2;
    }
    return app.exit(e);
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
  } catch (const std::system_error& e) {
    // fmt's print to stdout on a full disk or a closed pipe (`talus schema > /dev/full`; talus writes
    // its files through io_error-throwing writers): the output failed, not talus
    const int code = e.code().value();
    if (code == ENOSPC || code == EPIPE || code == EIO || code == EDQUOT || code == EFBIG) return stdout_failed(code);
    fmt::print(stderr, "talus: internal error: {}\n", e.what());
    return 4;
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

std::vector<std::string>& command_line() {
  static std::vector<std::string> words;
  return words;
}

void add_isa_option(CLI::App* command, const std::shared_ptr<std::string>& value) {
  // (an empty --isa, an unset shell variable, ran the automatic choice without a word)
  refuse_empty(command->add_option("--isa", *value,
                      "Vector path of the kernels: auto (the default: the best this CPU has) or one of " + [] {
                        std::string names;
                        for (const std::string& n : available_isas()) names += (names.empty() ? "" : ", ") + n;
                        return names;
                      }() + " (reference: the plain C++ path). Every path gives the same bits; also TALUS_ISA"),
               "give auto or a vector path, or leave --isa out");
}

void set_threads(int threads) {
  if (threads > 0) {
    omp_set_num_threads(threads);
    return;
  }
  // libgomp ignores an OMP_NUM_THREADS it cannot read (0, abc, 2.5: it warns as the program loads
  // and uses every core): refuse it, as --threads would. It is a list of positive whole numbers,
  // one a nesting level (4 or 4,2).
  if (const char* text = std::getenv("OMP_NUM_THREADS")) {
    const std::string value = text;
    bool readable = !value.empty();
    std::size_t at = 0;
    while (readable && at <= value.size()) {
      const std::size_t end = std::min(value.find(',', at), value.size());
      const std::string item = value.substr(at, end - at);
      const std::size_t first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
      const std::string digits = first == std::string::npos ? "" : item.substr(first, last - first + 1);
      readable = !digits.empty() && digits.find_first_not_of("0123456789") == std::string::npos &&
                 digits.find_first_not_of('0') != std::string::npos;
      // a number past libgomp's unsigned long it also ignores, and uses every core
      if (readable && (digits.size() > 9 || std::stoul(digits) > 4096))
        throw input_error(fmt::format("OMP_NUM_THREADS = {} is outside [1, 4096] (or give --threads)", value));
      at = end + 1;
    }
    if (!readable)
      throw input_error(fmt::format("OMP_NUM_THREADS = '{}' is not a whole number of threads in [1, 4096] "
                                    "(or give --threads)", value));
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
