#pragma once
// Each subcommand of the talus program lives in its own file and registers itself here.
// A command's callback does the work and throws talus::Error on failure; main() turns that into
// one line on stderr and the error's exit code (2 bad input, 3 instability).
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace talus::app {

void add_run_command(CLI::App& app);
void add_check_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_element_test_command(CLI::App& app);
void add_dem_springs_command(CLI::App& app);
void add_schema_command(CLI::App& app);

/// The exit code a command sets instead of calling exit(), so that main() returns it after MPI is
/// finalised (a run stopped by a signal exits with 128 + the signal); 0 by default.
int& exit_code();

/// The program's arguments as main() received them, the program's name first (a run's record,
/// run.json, names the command that made it).
std::vector<std::string>& command_line();

/// The --isa option of the commands that run the solver (core/simd_dispatch.hpp); apply it with
/// select_isa(*value) in the callback: "auto" (default) or a path of available_isas().
void add_isa_option(CLI::App* command, const std::shared_ptr<std::string>& value);
/// The OpenMP threads: `threads` (--threads) when > 0, else OMP_NUM_THREADS or all cores, refused
/// beyond 4096 as --threads is.
void set_threads(int threads);
/// Selects the kernels' vector path: `value` (the command's --isa) when given, else TALUS_ISA.
void select_isa_option(const std::string& value);

}  // namespace talus::app
