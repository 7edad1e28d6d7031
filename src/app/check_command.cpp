// `talus check SCENE`: validate a scene and print what a run would do, writing nothing.
#include "commands.hpp"
#include "disk_estimate.hpp"
#include "host_info.hpp"
#include "option_checks.hpp"
#include "run_checks.hpp"
#include "run_folder.hpp"
#include "talus/core/comm.hpp"
#include "talus/core/error.hpp"
#include "talus/diagnostics/flume_coordinates.hpp"
#include "talus/diagnostics/runout.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/memory_estimate.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>

#include <cstdio>
#include <optional>

namespace talus::app {

namespace {

// Where the runout will be measured from (diagnostics.runout): the gate and the runout plane as the run
// resolves them. A default runout plane at the last vertex of a measured profile (a 0.3 degree bend)
// was seen only in the run's closing line ("2.09 m short of the runout plane").
void print_runout_reference(const Scene& s) {
  const FlumeCoordinates c = flume_coordinates_of(s);
  const char* along = c.flat() ? "x" : "the terrain's arc length s";
  const std::string gate = s.runout.has_gate ? fmt::format("gate x = {} m (s = {:.6g} m)", s.runout.gate_x, c.s(s.runout.gate_x))
                                             : std::string("gate at the seeded bodies' front (no gate_x)");
  std::string plane;
  if (const auto x = runout_plane_x(s.runout, c, runout_grid_of(s)))
    plane = fmt::format("runout plane from x = {:.6g} m (s = {:.6g} m{})", *x, c.s(*x),
                        s.runout.has_runout_plane ? "" : "; the default: where the terrain's last straight segment starts");
  else
    plane = c.flat() && !s.runout.has_runout_plane ? "no runout plane (a flat grid: give runout_plane_x for one)"
                                                    : "no runout plane (the terrain's last straight segment starts outside the grid)";
  fmt::print("runout     measured along {}; {}; {}\n", along, gate, plane);
}

// What a run would do, from the scene and the memory estimate alone: nothing is seeded or
// allocated, so this answers at once on any scene (solver/memory_estimate.hpp).
void print_scene_summary(const Scene& s, const MemoryEstimate& memory, const MachineShare& share,
                         const DiskEstimate& disk, const std::string& out_dir) {
  const auto& g = s.grid;
  fmt::print("scene      {}{}\n", s.name, s.description.empty() ? "" : " - " + s.description);
  fmt::print("grid       {} x {} x {} cells of {} m, origin ({}, {}, {})\n", g.cells[0], g.cells[1], g.cells[2], g.h,
             g.origin[0], g.origin[1], g.origin[2]);
  fmt::print("particles  {} in {} bod{}\n", memory.particles, s.bodies.size(), s.bodies.size() == 1 ? "y" : "ies");
  fmt::print("method     {} with {} shape functions, Courant {}\n", to_string(s.scheme), to_string(s.shape), s.courant);
  const double dt = s.initial_time_step();
  // (a count past 10^15 in full was a line of 154 digits for a vanishing density)
  const double steps = estimated_steps(s);  // (as the disk line counts them: whole steps, time.max_steps)
  const auto count = [](double n) { return n < 1e15 ? fmt::format("{:.0f}", n) : fmt::format("{:.3g}", n); };
  // The work: particle-updates, the particles times the steps. The steps are counted at the initial
  // time step, the wave speed and velocities of the start: a flow that speeds up shortens the step
  // and takes more (the flowing runs of one user's landslide scenes took 36-45% more).
  fmt::print("time       end {} s, initial dt {:.3e} s: ~{} steps and ~{:.3g} particle-updates ({} particles x steps) "
             "at the initial time step; a flow that speeds up takes more\n",
             s.end_time, dt, count(steps), double(memory.particles) * steps, memory.particles);
  const std::optional<std::size_t> available = available_memory();
  fmt::print("memory     about {}: {} B per particle, {} of grid at the start (up to {} if the flow covers the whole "
             "grid); {}\n",
             format_bytes(double(memory.total())), memory.bytes_per_particle, format_bytes(double(memory.grid_bytes)),
             format_bytes(double(memory.grid_bytes_bound)),
             available ? format_bytes(double(*available)) + " available" : "available memory unknown");
  if (share.ranks > 1)  // (the line above is the whole scene's; the check is of each machine)
    fmt::print("memory     about {} on this machine ({} of the {} ranks{}), what the check compares\n",
               format_bytes(double(bytes_on_this_machine(s, memory, share))), share.ranks_here, share.ranks,
               share.root_here ? ", rank 0 among them, which gathers every particle" : "");
  fmt::print("disk       {}\n", disk.summary(out_dir));
  if (s.runout.enabled) print_runout_reference(s);
}

}  // namespace

void add_check_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("check", "Validate a scene file and print what a run would do (writes nothing)");
  auto scene_path = std::make_shared<std::string>();
  cmd->add_option("scene", *scene_path, "Scene file (JSON)")->required();
  // (taken as `talus run` takes them, so that `run` can be swapped for `check` on a command line)
  auto out_dir = std::make_shared<std::string>();
  auto threads = std::make_shared<int>(0);
  refuse_empty(cmd->add_option("--out", *out_dir, "The output folder talus run would use (default: runs/<scene name>): "
                                                  "the disk estimate and the folder's checks are of it"),
               "give a folder, or leave --out out for runs/<scene name>");
  check_range(cmd->add_option("--threads", *threads, "As talus run's: checked against the CPUs available"), 1, 4096);
  auto overwrite = std::make_shared<bool>(false);
  cmd->add_flag("--overwrite", *overwrite,
                "As talus run's: an unfinished run in the output folder is then no reason for the run to stop");
  // Run's options that change nothing check reports, taken (and their values checked as run checks
  // them) so that a run's whole command line checks as it is: a script that swapped `run` for `check`
  // in a line with --quiet met "talus check has no option --quiet" (a user's hunt). --restart is not
  // taken: check does not check a checkpoint, and its folder rules differ.
  auto isa = std::make_shared<std::string>();
  add_isa_option(cmd, isa);
  // (CLI11 writes the values into these: the callback holds them, as it holds the options it reads)
  struct RunOnly {
    bool quiet = false, foreground_frames = false;
    double progress_every = 0.0, stop_after = 0.0;
    std::string record_work;
    int record_interval = 1;
  };
  auto run_only = std::make_shared<RunOnly>();
  const char* group = "run's options (their values checked as run checks them; --record-work against the run's files)";
  cmd->add_flag("--quiet", run_only->quiet, "As talus run's")->group(group);
  cmd->add_flag("--foreground-frames", run_only->foreground_frames, "As talus run's")->group(group);
  check_range(cmd->add_option("--progress-every", run_only->progress_every, "As talus run's"), 0.1, 86400.0)->group(group);
  check_duration(cmd->add_option("--stop-after", run_only->stop_after, "As talus run's"))->group(group);
  CLI::Option* record_work = refuse_empty(cmd->add_option("--record-work", run_only->record_work, "As talus run's"),
                                          "give a file, or leave --record-work out")
                                 ->group(group);
  check_range(cmd->add_option("--record-interval", run_only->record_interval, "As talus run's"), 1, 1000000)
      ->needs(record_work)
      ->group(group);
  cmd->footer("The memory available is the smaller of MemAvailable and a cgroup's (container, batch job) limit; the "
              "environment variable TALUS_MEMORY_LIMIT (bytes, or with a K/M/G/T suffix) sets it instead, e.g. a "
              "share of a node for one run. A scene that does not fit is refused (exit code 2), as talus run refuses it; so is an output folder "
              "(--out, or runs/<scene name>) that talus run would refuse (an unfinished run's, a folder in place of "
              "an output), after the summary.");
  cmd->callback([=]() {
    select_isa_option(*isa);  // (an --isa this CPU lacks is refused as run refuses it)
    // Under mpirun every rank checks (an error is printed once, main.cpp); rank 0 alone prints.
    const Comm world = Comm::world();
    const Scene scene = read_scene_file(*scene_path);
    available_memory();  // a bad TALUS_MEMORY_LIMIT stops here, not halfway through the summary
    Solver::check_ranks(scene, world.size());  // what `mpirun -np N talus run` would refuse
    const MachineShare share = machine_share(world, "");  // (collective)
    // the threads a run would take by default (under mpirun: shared among a host's ranks), and a host
    // they would oversubscribe (OMP_NUM_THREADS beyond its CPUs), said with the scene's warnings
    const std::optional<std::string> oversubscribed =
        oversubscription_warning(world, *threads, set_rank_threads(*threads, world));
    const MemoryEstimate memory = estimate_memory(scene);
    // every rank checks its machine, as `talus run` does (rank 0 alone said ok where a rank's
    // smaller machine then refused the run); the refusal comes after the summary on one rank
    if (world.distributed()) world.agree([&] { require_memory_fits(scene, memory, share); });
    if (!world.root()) return;
    // (where `talus run` writes by default; --out names another folder) The disk's warning is
    // `talus run`'s (check said ok where the run warned of 215 GB of frames), with the scene's.
    const std::string dir = out_dir->empty() ? "runs/" + scene.name : *out_dir;
    const DiskEstimate disk = estimate_disk(scene, memory.particles, dir);
    std::vector<std::string> more;
    if (const auto w = disk_warning(disk, dir)) more.push_back(*w);
    if (const auto w = memory_bound_warning(memory, share)) more.push_back(*w);
    if (oversubscribed) more.push_back(*oversubscribed);
    const std::size_t warnings = print_warnings(scene, more);
    print_scene_summary(scene, memory, share, disk, dir);
    // (check said ok, and the run stopped at once: the default folder held this scene file, or
    // could not be made here, or held an unfinished run. It then said ok with a note and exited 0,
    // and a script that gated on check met run's exit code 2: the run's refusal is check's error.)
    std::optional<std::string> run_would_stop;
    try {
      require_outputs_spare_inputs(dir, *scene_path, scene, "", run_only->record_work);
      require_no_folder_in_place_of_an_output(dir);
      check_writable_folder(dir, "output folder");
      require_no_unfinished_run(dir, *overwrite);
    } catch (const Error& e) {
      run_would_stop = fmt::format("talus run {} would stop: {}", out_dir->empty() ? "without --out" : "with this --out", e.what());
    }
    if (!world.distributed()) require_memory_fits(scene, memory, share);  // (under mpirun: checked above, on every rank)
    if (run_would_stop) {
      std::fflush(stdout);  // (the summary before the error line, in a log that holds both)
      throw input_error(*run_would_stop);
    }
    // (a bare "ok" last, on stdout, hid the warnings on stderr: it counts them)
    const std::string ranks = world.distributed() ? fmt::format("for {} ranks", world.size()) : "";
    const std::string warned =
        warnings == 0 ? "" : fmt::format("{} warning{} above, on stderr", warnings, warnings == 1 ? "" : "s");
    fmt::print("ok{}\n", ranks.empty() && warned.empty() ? std::string()
                                                           : fmt::format(" ({}{}{})", ranks, ranks.empty() || warned.empty() ? "" : "; ", warned));
  });
}

}  // namespace talus::app
